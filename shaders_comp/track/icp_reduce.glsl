// Tracking, one ICP iteration at one level, part 1: projective data association and the point-to-plane terms
// of every pixel, summed per workgroup.
// For a frame pixel with a point p and normal m (camera space): p_w = T p with T the pose estimated so far
// (TrackPush::cameraToWorld, or TrackStateGpu's in the GPU-solved mode); p_w is projected into the model
// maps (drawn at the model pose); the model point q and normal n there are associated when
// |p_w - q| <= distanceGate and (R m) . n >= normalGateCos. Residual r = n . (p_w - q); J = [(p_w - c) x n, n]
// its derivative for a rotation about the camera's centre c and a translation (both in world axes); Huber
// weight w. Gates and Huber delta are the level's (TrackPush). Each invocation sums
// TrackParamsGpu::pixelsPerInvocation pixels in order, then the workgroup adds its invocations' sums by a
// fixed binary tree in shared memory: the order of every addition is fixed, so the partials are the same bit
// for bit on every run (no float atomics). track_icp_sum adds the partials up.
#ifndef VKMESH_TRACK_ICP_REDUCE_GLSL
#define VKMESH_TRACK_ICP_REDUCE_GLSL
#include "track/track_common.glsl"

// The per-pixel maps: texel fetches (TRACK_READ_TEXELS, track_icp_reduce.comp) or SSBO loads
// (track_icp_reduce_buffers.comp, for a device whose maxTexelBufferElements is below the pyramid's pixels).
#ifdef TRACK_READ_TEXELS
layout(set = 0, binding = TRACK_BINDING_VERTEX_TEXELS) uniform samplerBuffer vertexTexels;
layout(set = 0, binding = TRACK_BINDING_NORMAL_TEXELS) uniform samplerBuffer normalTexels;
layout(set = 0, binding = TRACK_BINDING_MODEL_POSITION_TEXELS) uniform samplerBuffer modelPositionTexels;
layout(set = 0, binding = TRACK_BINDING_MODEL_NORMAL_TEXELS) uniform samplerBuffer modelNormalTexels;
layout(set = 0, binding = TRACK_BINDING_INTENSITY_TEXELS) uniform samplerBuffer intensityTexels;
layout(set = 0, binding = TRACK_BINDING_MODEL_INTENSITY_TEXELS) uniform samplerBuffer modelIntensityTexels;
vec4 framePoint(uint i) { return texelFetch(vertexTexels, int(i)); }
vec4 frameNormal(uint i) { return texelFetch(normalTexels, int(i)); }
vec4 modelPosition(uint i) { return texelFetch(modelPositionTexels, int(i)); }
vec4 modelNormal(uint i) { return texelFetch(modelNormalTexels, int(i)); }
float frameIntensity(uint i) { return texelFetch(intensityTexels, int(i)).x; }
float modelIntensityAt(uint i) { return texelFetch(modelIntensityTexels, int(i)).x; }
#else
vec4 framePoint(uint i) { return vertexPyramid[i]; }
vec4 frameNormal(uint i) { return normalPyramid[i]; }
vec4 modelPosition(uint i) { return modelPositions[i]; }
vec4 modelNormal(uint i) { return modelNormals[i]; }
float frameIntensity(uint i) { return intensityPyramid[i]; }
float modelIntensityAt(uint i) { return modelIntensity[i]; }
#endif

layout(local_size_x = WG_TRACK_REDUCE) in;

shared float tree[TRACK_SUM_COUNT * WG_TRACK_REDUCE];

// The invocation's sums. A global, and indexed only by constants once the loops below are unrolled, so that
// the compiler keeps it in registers (llvmpipe put an array passed `inout` in memory, copied at every call).
float acc[TRACK_SUM_COUNT];

// Adds w J^T J and w J^T r of one residual r with J = [jr, jt] to the invocation's sums.
void addTerm(vec3 jr, vec3 jt, float r, float w) {
    float J[6] = float[6](jr.x, jr.y, jr.z, jt.x, jt.y, jt.z);
    [[unroll]] for (uint a = 0u; a < 6u; ++a) {
        precise float wa = w * J[a];
        // Row a of the upper triangle starts at a * 6 - a * (a - 1) / 2.
        [[unroll]] for (uint b = a; b < 6u; ++b) acc[TRACK_SUM_JTJ + a * 6u - (a * (a - 1u)) / 2u + (b - a)] += wa * J[b];
        acc[TRACK_SUM_JTR + a] += wa * r;
    }
}

void main() {
    // Uniform over the dispatch, so the whole workgroup leaves before any barrier.
    if (levelStopped()) return;
    // The estimate: the host's (push constants), or the GPU-solved mode's, which the last solve pass moved.
    vec4 estimate[3] = pass.cameraToWorld;
    if (solvedOnGpu()) estimate = state.cameraToWorld;
    uvec2 size = levelSize();
    bool checkerboard = (pass.flags & TRACK_FLAG_CHECKERBOARD) != 0u;
    uint pixels = checkerboard ? (size.x / 2u) * size.y : size.x * size.y;
    uint lane = gl_LocalInvocationID.x;
    [[unroll]] for (uint k = 0u; k < TRACK_SUM_COUNT; ++k) acc[k] = 0.0;

    uint perInvocation = min(track.pixelsPerInvocation, TRACK_MAX_PIXELS_PER_INVOCATION);
    for (uint k = 0u; k < TRACK_MAX_PIXELS_PER_INVOCATION; ++k) {
        if (k >= perInvocation) break;
        uint i = (gl_WorkGroupID.x * perInvocation + k) * WG_TRACK_REDUCE + lane;
        if (i >= pixels) continue;
        if (checkerboard) {   // the i-th pixel with x + y even, row by row
            uint y = i / (size.x / 2u);
            i = y * size.x + 2u * (i % (size.x / 2u)) + (y & 1u);
        }
        uint index = pass.offset + i;
        vec4 point = framePoint(index);
        vec4 normal = frameNormal(index);
        if (point.w == 0.0 || normal.w == 0.0) continue;
        acc[TRACK_SUM_VALID] += 1.0;
        precise vec3 world = transformPoint(estimate, point.xyz);
        precise vec3 model = transformPoint(track.modelWorldToCamera, world);
        if (!(model.z > 0.0)) continue;
        precise float u = pass.intrinsics.x * (model.x / model.z) + pass.intrinsics.z;
        precise float v = pass.intrinsics.y * (model.y / model.z) + pass.intrinsics.w;
        // Pixel centres are at integer coordinates in the intrinsics' convention: round to the nearest.
        float fu = floor(u + 0.5), fv = floor(v + 0.5);
        if (!(fu >= 0.0 && fv >= 0.0 && fu < float(size.x) && fv < float(size.y))) continue;
        uint modelIndex = pass.offset + uint(fv) * size.x + uint(fu);
        vec4 q = modelPosition(modelIndex);
        if (q.w == 0.0) continue;
        acc[TRACK_SUM_MODEL_HITS] += 1.0;
        vec3 n = modelNormal(modelIndex).xyz;
        precise vec3 diff = world - q.xyz;
        precise float distance2 = dot(diff, diff);
        if (distance2 > pass.distanceGate * pass.distanceGate) continue;
        precise vec3 frameNormal = rotateVector(estimate, normal.xyz);
        if (dot(frameNormal, n) < pass.normalGateCos) continue;
        precise float r = dot(n, diff);
        precise float w = abs(r) <= pass.huberDelta ? 1.0 : pass.huberDelta / abs(r);
        precise vec3 centre = vec3(estimate[0].w, estimate[1].w, estimate[2].w);
        precise vec3 lever = world - centre;
        addTerm(cross(lever, n), n, r, w);
        acc[TRACK_SUM_WEIGHTED_ERROR] += w * r * r;
        acc[TRACK_SUM_INLIERS] += 1.0;
        acc[TRACK_SUM_SQUARED_ERROR] += r * r;

        // The photometric term, for a pixel the geometry associated: the model's intensity, bilinear at the
        // projection (all four pixels around it coloured), minus the frame's. Its gradient a in world space
        // (the image gradient through the projection and the model camera's rotation) takes the place of n:
        // J = [(p - c) x a, a].
        if (track.colorWeight <= 0.0 || track.frameHasColor == 0u) continue;
        float intensity = frameIntensity(index);
        float x0 = floor(u), y0 = floor(v);
        if (!(intensity >= 0.0 && x0 >= 0.0 && y0 >= 0.0 && x0 + 1.0 < float(size.x) && y0 + 1.0 < float(size.y))) continue;
        uint corner = pass.offset + uint(y0) * size.x + uint(x0);
        float i00 = modelIntensityAt(corner), i10 = modelIntensityAt(corner + 1u);
        float i01 = modelIntensityAt(corner + size.x), i11 = modelIntensityAt(corner + size.x + 1u);
        if (min(min(i00, i10), min(i01, i11)) < 0.0) continue;
        precise float tx = u - x0, ty = v - y0;
        precise float top = i00 + tx * (i10 - i00);
        precise float bottom = i01 + tx * (i11 - i01);
        precise float rc = top + ty * (bottom - top) - intensity;
        precise float gx = (i10 - i00) + ty * ((i11 - i01) - (i10 - i00));
        precise float gy = bottom - top;
        precise float iz = 1.0 / model.z;
        precise vec3 gradCamera = vec3(gx * pass.intrinsics.x * iz, gy * pass.intrinsics.y * iz,
                                       -(gx * pass.intrinsics.x * model.x + gy * pass.intrinsics.y * model.y) * iz * iz);
        precise vec3 a = rotateVectorTransposed(track.modelWorldToCamera, gradCamera);
        precise float wc = track.colorWeight * (abs(rc) <= track.colorHuber ? 1.0 : track.colorHuber / abs(rc));
        addTerm(cross(lever, a), a, rc, wc);
        acc[TRACK_SUM_WEIGHTED_ERROR] += wc * rc * rc;
    }

    [[unroll]] for (uint k = 0u; k < TRACK_SUM_COUNT; ++k) tree[k * WG_TRACK_REDUCE + lane] = acc[k];
    for (uint stride = WG_TRACK_REDUCE / 2u; stride > 0u; stride /= 2u) {
        barrier();
        if (lane < stride)
            for (uint k = 0u; k < TRACK_SUM_COUNT; ++k) tree[k * WG_TRACK_REDUCE + lane] += tree[k * WG_TRACK_REDUCE + lane + stride];
    }
    barrier();
    if (lane < TRACK_SUM_COUNT) partials[gl_WorkGroupID.x * TRACK_SUM_COUNT + lane] = tree[lane * WG_TRACK_REDUCE];
}
#endif
