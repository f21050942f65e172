// Component: the block store (src/gpu/block_store.h). A pool of blocks, each the TSDF (distance and weight)
// (and colour) at its 512 cube corners, block-major, x fastest; the block's coordinate and hash slot; the free list of
// unused blocks (a stack popped from its top).
#ifndef VKMESH_BLOCK_STORE_GLSL
#define VKMESH_BLOCK_STORE_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_BLOCK_COORDS) buffer BlockCoords { ivec4 blockCoords[]; };   // xyz, w = hash slot
layout(std430, set = 0, binding = BINDING_VOXEL_SDF) buffer VoxelSdf { float voxelSdf[]; };
layout(std430, set = 0, binding = BINDING_VOXEL_WEIGHT) buffer VoxelWeight { float voxelWeight[]; };
// Colour per corner (voxel_color.glsl's encoding); a 16-byte placeholder when colour is off (colorMode).
layout(std430, set = 0, binding = BINDING_VOXEL_COLOR) buffer VoxelColor { uint voxelColor[]; };
layout(std430, set = 0, binding = BINDING_FREE_LIST) buffer FreeList { uint freeList[]; };

// Index of corner (x, y, z) of a block in the voxel arrays: x fastest.
uint voxelIndex(uint block, uvec3 local) {
    return block * VOXELS_PER_BLOCK + (local.z * BLOCK_SIDE + local.y) * BLOCK_SIDE + local.x;
}
#endif
