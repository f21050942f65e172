#version 450
// Tracking, the last pass when a frame is fused in the submission that tracks it (docs/TRACKING.md, "One
// submission"): PoseTracker's loss policy applied on the GPU to level 0's last system and the estimate that
// track_icp_solve left (the CPU reference is trackingLoss() in src/gpu/tracking/pose_tracker.cpp: the same
// checks in the same order), and the frame's pose written where the volume's passes read it (FramePoseGpu): the
// estimate, or skip = 1 when the frame is lost, so that nothing is fused and the map stays bit-identical.
// One invocation.
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(std430, set = 0, binding = TRACK_BINDING_FRAME_POSE) writeonly buffer FramePoseBuffer { FramePoseGpu framePose; };

layout(local_size_x = 1) in;

// Smallest over largest eigenvalue of level 0's last 6x6 system, as solveIcpStep's conditioning
// (core/icp_solve.cpp, in double there): cyclic Jacobi rotations, 10 sweeps of 15 (a 6x6 matrix is diagonal to
// float precision after 6 to 8); 0 when the system is not finite or has no positive eigenvalue.
float conditioningOfFinalSystem() {
    float A[6][6];
    uint slot = TRACK_SUM_JTJ;
    for (uint i = 0u; i < 6u; ++i) {
        for (uint j = i; j < 6u; ++j) {
            float v = state.finalSums[slot++];
            if (isnan(v) || isinf(v)) return 0.0;
            A[i][j] = v;
            A[j][i] = v;
        }
    }
    for (uint sweep = 0u; sweep < 10u; ++sweep) {
        for (uint p = 0u; p < 5u; ++p) {
            for (uint q = p + 1u; q < 6u; ++q) {
                float apq = A[p][q];
                if (apq == 0.0) continue;
                // The rotation that zeroes A[p][q] (the smaller angle); t = tan of it.
                float theta = (A[q][q] - A[p][p]) / (2.0 * apq);
                float t = abs(theta) > 1e15 ? 0.5 / theta
                                            : (theta >= 0.0 ? 1.0 : -1.0) / (abs(theta) + sqrt(theta * theta + 1.0));
                float c = inversesqrt(t * t + 1.0), s = t * c;
                for (uint k = 0u; k < 6u; ++k) {
                    float akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq;
                    A[k][q] = s * akp + c * akq;
                }
                for (uint k = 0u; k < 6u; ++k) {
                    float apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk;
                    A[q][k] = s * apk + c * aqk;
                }
            }
        }
    }
    float largest = A[0][0], smallest = A[0][0];
    for (uint i = 1u; i < 6u; ++i) {
        largest = max(largest, A[i][i]);
        smallest = min(smallest, A[i][i]);
    }
    return largest > 0.0 ? max(0.0, smallest) / largest : 0.0;
}

void main() {
    float valid = state.finalSums[TRACK_SUM_VALID];
    float hits = state.finalSums[TRACK_SUM_MODEL_HITS];
    float inliers = state.finalSums[TRACK_SUM_INLIERS];
    float rmse = inliers > 0.0 ? sqrt(state.finalSums[TRACK_SUM_SQUARED_ERROR] / inliers) : 0.0;
    float conditioning = conditioningOfFinalSystem();

    // The motion since the last tracked frame: inverse(last) * estimate.
    mat3 last = mat3(track.lastTrackedCameraToWorld[0].xyz, track.lastTrackedCameraToWorld[1].xyz,
                     track.lastTrackedCameraToWorld[2].xyz);   // columns = rows of R: this is R^T
    mat3 estimate = transpose(mat3(state.cameraToWorld[0].xyz, state.cameraToWorld[1].xyz, state.cameraToWorld[2].xyz));
    vec3 lastT = vec3(track.lastTrackedCameraToWorld[0].w, track.lastTrackedCameraToWorld[1].w, track.lastTrackedCameraToWorld[2].w);
    vec3 estimateT = vec3(state.cameraToWorld[0].w, state.cameraToWorld[1].w, state.cameraToWorld[2].w);
    mat3 turn = last * estimate;   // R_last^T R
    float jump = length(last * (estimateT - lastT));
    // atan2 of the angle's sine and cosine, as rotationDegrees (core/icp_solve.cpp).
    float sine = 0.5 * length(vec3(turn[1][2] - turn[2][1], turn[2][0] - turn[0][2], turn[0][1] - turn[1][0]));
    float cosine = 0.5 * (turn[0][0] + turn[1][1] + turn[2][2] - 1.0);
    float degrees = atan(sine, cosine) * (180.0 / 3.14159265358979);

    uint reason = TRACK_TRACKED;
    if (valid == 0.0) reason = TRACK_LOST_NO_DEPTH;
    else if (hits == 0.0) reason = TRACK_LOST_NO_MODEL;
    else if (inliers < track.minInliers || inliers < track.minInlierFraction * valid) reason = TRACK_LOST_FEW_INLIERS;
    else if ((state.unsolvedLevels & 1u) != 0u || !(conditioning >= track.minConditioning)) reason = TRACK_LOST_ILL_CONDITIONED;
    else if (!(jump <= track.maxJumpMetres)) reason = TRACK_LOST_JUMP;
    else if (!(degrees <= track.maxJumpDegrees)) reason = TRACK_LOST_TURN;
    else if (track.recentRmse > 0.0 && rmse > track.minErrorForRise && rmse > track.maxErrorRise * track.recentRmse)
        reason = TRACK_LOST_ERROR_ROSE;
    else if (inliers < track.minShareOfRecent * track.recentInlierShare * valid) reason = TRACK_LOST_SHARE_FELL;
    state.lostReason = reason;
    state.conditioning = conditioning;

    // [R | t] and its inverse [R^T | -R^T t], rows.
    mat3 rt = transpose(estimate);
    vec3 back = -(rt * estimateT);
    for (uint r = 0u; r < 3u; ++r) {
        framePose.cameraToWorld[r] = state.cameraToWorld[r];
        framePose.worldToCamera[r] = vec4(estimate[r], back[r]);   // column r of R = row r of R^T
    }
    framePose.skip = reason == TRACK_TRACKED ? 0u : 1u;
    framePose.deintegrate = 0u;   // a tracked frame is fused
    framePose.pad1 = 0u;
    framePose.pad2 = 0u;
}
