#version 450
// Tracking, pass 2 (once per coarser level): level l+1 of the depth pyramid from level l. Each coarse pixel
// averages the 2 x 2 fine pixels that lie within 3 filter sigmas of the first measured one, so a depth edge is
// not blurred into a surface that is not there. The frame's intensity (when it has colour) is averaged too.
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(local_size_x = WG_TRACK_PIXELS_X, local_size_y = WG_TRACK_PIXELS_Y) in;

void main() {
    uvec2 size = levelSize();
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    float samples[4];
    [[unroll]] for (uint k = 0u; k < 4u; ++k) {
        uvec2 q = pixel * 2u + uvec2(k & 1u, k >> 1u);
        samples[k] = depthPyramid[pass.finerOffset + q.y * pass.finerWidth + q.x];
    }
    float reference = 0.0;
    [[unroll]] for (uint k = 0u; k < 4u; ++k)
        if (reference == 0.0 && samples[k] > 0.0) reference = samples[k];
    precise float sum = 0.0;
    float count = 0.0;
    [[unroll]] for (uint k = 0u; k < 4u; ++k) {
        if (samples[k] > 0.0 && abs(samples[k] - reference) <= 3.0 * track.filterDepthSigma) {
            sum += samples[k];
            count += 1.0;
        }
    }
    depthPyramid[pass.offset + pixel.y * size.x + pixel.x] = count > 0.0 ? sum / count : 0.0;
    // The frame's intensity (photometric term): the mean of the 2 x 2 pixels that have one.
    if (track.frameHasColor != 0u) {
        precise float intensity = 0.0;
        float have = 0.0;
        [[unroll]] for (uint k = 0u; k < 4u; ++k) {
            uvec2 q = pixel * 2u + uvec2(k & 1u, k >> 1u);
            float i = intensityPyramid[pass.finerOffset + q.y * pass.finerWidth + q.x];
            if (i >= 0.0) intensity += i, have += 1.0;
        }
        intensityPyramid[pass.offset + pixel.y * size.x + pixel.x] = have > 0.0 ? intensity / have : -1.0;
    }
}
