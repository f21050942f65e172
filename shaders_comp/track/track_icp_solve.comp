#version 450
// Tracking, one ICP iteration, part 3 of the GPU-solved mode (docs/TRACKING.md, "One submission"): the 6x6
// system from track_icp_sum's sums, solved and applied to the estimate in TrackStateGpu, so that the next
// iteration's passes read the moved estimate without the host. One invocation (36 numbers). The host-solved
// mode does the same in double (core/icp_solve.cpp: solveIcpStep, applyTwist); here in float, with the
// system equilibrated (scaled to a unit diagonal) before a Cholesky factorisation so that the rotation and
// translation unknowns, of different units, lose no more precision than the float sums already have.
// A level stops, as on the host, after a tiny step (applied) or at a system that cannot be solved (not
// applied; its bit in unsolvedLevels).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "track/track_common.glsl"

layout(local_size_x = 1) in;

void main() {
    if (levelStopped()) return;
    uint level = passLevel();
    if (level == 0u)
        [[unroll]] for (uint k = 0u; k < TRACK_SUM_COUNT; ++k) state.finalSums[k] = sums[k];
    state.iterations += 1u;

    // The normal equations A x = -b (A symmetric: its upper triangle row by row in the sums).
    float A[6][6];
    float b[6];
    uint slot = TRACK_SUM_JTJ;
    [[unroll]] for (uint i = 0u; i < 6u; ++i) {
        [[unroll]] for (uint j = i; j < 6u; ++j) {
            A[i][j] = sums[slot];
            A[j][i] = sums[slot];
            ++slot;
        }
        b[i] = sums[TRACK_SUM_JTR + i];
    }
    bool ok = sums[TRACK_SUM_INLIERS] >= 6.0;
    // Equilibration: D A D with D = diag(1 / sqrt(A_ii)).
    float d[6];
    [[unroll]] for (uint i = 0u; i < 6u; ++i) {
        ok = ok && A[i][i] > 0.0 && !isinf(A[i][i]);
        d[i] = ok ? inversesqrt(A[i][i]) : 0.0;
    }
    // Cholesky L L^T of D A D (lower triangle of L kept in A); a pivot that is not positive: singular.
    [[unroll]] for (uint j = 0u; j < 6u; ++j) {
        precise float pivot = A[j][j] * d[j] * d[j];
        [[unroll]] for (uint k = 0u; k < j; ++k) pivot -= A[j][k] * A[j][k];
        ok = ok && pivot > 1e-7;   // float: a smaller pivot is rounding, not information
        float l = ok ? sqrt(pivot) : 1.0;
        A[j][j] = l;
        [[unroll]] for (uint i = j + 1u; i < 6u; ++i) {
            precise float v = A[i][j] * d[i] * d[j];
            [[unroll]] for (uint k = 0u; k < j; ++k) v -= A[i][k] * A[j][k];
            A[i][j] = v / l;
        }
    }
    // L y = -D b, L^T z = y, x = D z.
    float y[6];
    [[unroll]] for (uint i = 0u; i < 6u; ++i) {
        precise float v = -b[i] * d[i];
        [[unroll]] for (uint k = 0u; k < i; ++k) v -= A[i][k] * y[k];
        y[i] = v / A[i][i];
    }
    float x[6];
    [[unroll]] for (int i = 5; i >= 0; --i) {
        precise float v = y[i];
        [[unroll]] for (int k = i + 1; k < 6; ++k) v -= A[k][i] * x[k];
        x[i] = v / A[i][i];
    }
    [[unroll]] for (uint i = 0u; i < 6u; ++i) {
        x[i] *= d[i];
        ok = ok && !isnan(x[i]) && !isinf(x[i]);
    }
    if (!ok) {
        state.unsolvedLevels |= 1u << level;
        state.stoppedLevel = level + 1u;
        return;
    }

    // The step: R' = exp(omega) R (about the camera's own centre), t' = t + translation (core/icp_solve.cpp,
    // applyTwist). Rodrigues with the series for small angles, where sin(a) / a and (1 - cos a) / a^2 lose
    // their digits in float.
    vec3 omega = vec3(x[0], x[1], x[2]);
    vec3 translation = vec3(x[3], x[4], x[5]);
    float angle2 = dot(omega, omega);
    float s, c;
    if (angle2 < 1e-6) {
        s = 1.0 - angle2 / 6.0;
        c = 0.5 - angle2 / 24.0;
    } else {
        float angle = sqrt(angle2);
        s = sin(angle) / angle;
        c = (1.0 - cos(angle)) / angle2;
    }
    // exp(omega) = I + s K + c K^2, K the cross-product matrix of omega.
    mat3 K = mat3(0.0, omega.z, -omega.y, -omega.z, 0.0, omega.x, omega.y, -omega.x, 0.0);   // columns
    mat3 step = mat3(1.0) + s * K + c * (K * K);
    mat3 R = transpose(mat3(state.cameraToWorld[0].xyz, state.cameraToWorld[1].xyz, state.cameraToWorld[2].xyz));
    mat3 moved = step * R;
    // Keep the rotation orthonormal over many float steps: Gram-Schmidt on its rows (the host uses an SVD).
    vec3 r0 = normalize(vec3(moved[0][0], moved[1][0], moved[2][0]));
    vec3 r1 = vec3(moved[0][1], moved[1][1], moved[2][1]);
    r1 = normalize(r1 - dot(r0, r1) * r0);
    vec3 r2 = cross(r0, r1);
    vec3 t = vec3(state.cameraToWorld[0].w, state.cameraToWorld[1].w, state.cameraToWorld[2].w) + translation;
    state.cameraToWorld[0] = vec4(r0, t.x);
    state.cameraToWorld[1] = vec4(r1, t.y);
    state.cameraToWorld[2] = vec4(r2, t.z);
    if (sqrt(angle2) < track.stopRotation && length(translation) < track.stopTranslation) state.stoppedLevel = level + 1u;
}
