#version 450
// Tracking, one ICP iteration, part 2: the workgroups' partial sums added up, one invocation per value, in
// workgroup order with Kahan compensation: a fixed order, so the same bits every run. The host reads the
// TRACK_SUM_COUNT sums and solves the 6x6 system in double (or track_icp_solve does, on the GPU). TrackPush::size
// holds the number of partials.
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(local_size_x = TRACK_SUM_COUNT) in;

void main() {
    if (levelStopped()) return;
    uint value = gl_LocalInvocationID.x;
    uint groups = min(pass.size, TRACK_MAX_PARTIALS);
    precise float sum = 0.0;
    precise float compensation = 0.0;
    for (uint g = 0u; g < groups; ++g) {
        precise float y = partials[g * TRACK_SUM_COUNT + value] - compensation;
        precise float t = sum + y;
        compensation = (t - sum) - y;
        sum = t;
    }
    sums[value] = sum;
}
