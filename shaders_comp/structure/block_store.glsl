// Component: the block store (src/gpu/block_store.h). A pool of blocks, each the TSDF (the fixed-point sum of
// the fused distances and their count, shared_layout.h "A TSDF corner") (and colour) at its 512 cube corners, block-major, x fastest; the block's coordinate and hash slot; the free list of
// unused blocks (a stack popped from its top).
#ifndef VKMESH_BLOCK_STORE_GLSL
#define VKMESH_BLOCK_STORE_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_BLOCK_COORDS) buffer BlockCoords { ivec4 blockCoords[]; };   // xyz, w = hash slot
layout(std430, set = 0, binding = BINDING_VOXEL_SDF) buffer VoxelSdfSum { int voxelSdfSum[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_WEIGHT) buffer VoxelWeight { float voxelWeight[]; };
// Colour per corner (voxel_color.glsl's encoding); a 16-byte placeholder when colour is off (colorMode).
layout(std430, set = 0, binding = BINDING_VOXEL_COLOR) buffer VoxelColor { uint voxelColor[]; };
layout(std430, set = 0, binding = BINDING_FREE_LIST) buffer FreeList { uint freeList[]; };
// The same voxel arrays four corners at a time (x to x + 3 of a row): the corners of one invocation of a
// workgroup-per-block pass (cornerOfInvocation), read and written with one access each. On llvmpipe an access
// costs about the same whatever its width: fusion 3.6 -> 2.8 ms on the synthetic room with these instead of 12
// scalar accesses per invocation (docs/PORTABILITY.md).
layout(std430, set = 0, binding = BINDING_VOXEL_SDF) buffer VoxelSdfSum4 { ivec4 voxelSdfSum4[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_WEIGHT) buffer VoxelWeight4 { vec4 voxelWeight4[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_COLOR) buffer VoxelColor4 { uvec4 voxelColor4[]; };

// A corner's distance in metres from its sum (steps) and count: 0 without observations. The CPU twin is
// tsdfMean in src/core/tsdf_corner.h (same operations, same order).
float tsdfMean(int sum, float weight) {
    if (weight <= 0.0) return 0.0;
    precise float steps = float(sum) / weight;
    precise float metres = steps * params.sdfMetresPerStep;
    return metres;
}
float cornerSdf(uint v) { return tsdfMean(voxelSdfSum[v], voxelWeight[v]); }

// One observation's truncated distance (metres, in [-truncation, truncation]) as a whole number of steps.
int tsdfSteps(float tsdf) {
    precise float scaled = tsdf * params.sdfStepsPerMetre + 0.5;
    float limit = float(SDF_STEPS_PER_TRUNCATION);
    return int(clamp(floor(scaled), -limit, limit));
}

// Recycling's starvation: the sum after the weight drops from oldWeight to newWeight, keeping the distance
// (rounded, never across zero). CPU twin: starvedSum in src/core/tsdf_corner.h.
int starvedSum(int sum, float oldWeight, float newWeight) {
    if (newWeight <= 0.0) return 0;
    precise float scaled = float(sum) / oldWeight * newWeight + 0.5;
    int s = int(floor(scaled));
    return sum < 0 ? min(s, -1) : (sum > 0 ? max(s, 1) : 0);
}

// In a workgroup-per-block pass over the corners (fuse_depth, recycle_retire), invocation lid holds the
// VOXELS_PER_INVOCATION consecutive corners lid * VOXELS_PER_INVOCATION + k: one element of the four-corner views
// above (its index: cornerQuadOfInvocation), and one nibble of a mask word (frame_lists.glsl).
uint cornerOfInvocation(uint k) { return gl_LocalInvocationIndex * VOXELS_PER_INVOCATION + k; }
uint cornerQuadOfInvocation(uint block) { return block * (VOXELS_PER_BLOCK / VOXELS_PER_INVOCATION) + gl_LocalInvocationIndex; }

// Index of corner (x, y, z) of a block in the voxel arrays: x fastest.
uint voxelIndex(uint block, uvec3 local) {
    return block * VOXELS_PER_BLOCK + (local.z * BLOCK_SIDE + local.y) * BLOCK_SIDE + local.x;
}
#endif
