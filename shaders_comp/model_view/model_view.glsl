// The model-in-view passes' own descriptor set (shared_layout.h, "the model in a view"). Same rules as
// structure/frame.glsl: no waiting, bounded loops.
#ifndef VKMESH_HASH32
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require   // shared_layout.h declares 64-bit constants
#endif
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require

#include "shared_layout.h"

layout(std430, set = 0, binding = VIEW_BINDING_BLOCK_COORDS) readonly buffer BlockCoords { ivec4 blockCoords[]; };
layout(std430, set = 0, binding = VIEW_BINDING_HASH_VALUES) readonly buffer HashValues { uint hashValues[]; };
layout(std430, set = 0, binding = VIEW_BINDING_CUBE_STATE) readonly buffer CubeStates { uvec4 cubeStates[]; };   // 4 cubes each
layout(std430, set = 0, binding = VIEW_BINDING_CHUNKS) readonly buffer ChunkTriangles { uint chunkTriangles[]; };
layout(std430, set = 0, binding = VIEW_BINDING_BLOCK_LIST) buffer BlockList { uint viewBlocks[]; };
layout(std430, set = 0, binding = VIEW_BINDING_CHUNK_LIST) buffer ChunkList { uint viewChunks[]; };
layout(std430, set = 0, binding = VIEW_BINDING_INDICES) writeonly buffer ViewIndices { uint viewIndices[]; };
layout(std430, set = 0, binding = VIEW_BINDING_STATE) buffer ViewStateBuffer { ModelViewState viewState; };
layout(std430, set = 0, binding = VIEW_BINDING_VERTICES) readonly buffer Vertices { Vertex vertices[]; };

layout(push_constant) uniform PushBlock {
    vec4 worldToCamera[3];
    vec4 intrinsics;
    vec4 viewport;
    float blockSide;
    float blockRadius;
    uint blockCapacity;
    uint hashCapacity;
    uint createdBefore;
} pc;

// `count` items of this invocation appended to a list whose length is `counter`: the first one's position. One
// atomic per subgroup (called in uniform control flow).
#define APPEND_PER_SUBGROUP(counter, count, first) {                            \
        uint offset_ = subgroupExclusiveAdd(count);                               \
        uint total_ = subgroupAdd(count);                                         \
        uint base_ = 0u;                                                          \
        if (subgroupElect() && total_ != 0u) base_ = atomicAdd(counter, total_);  \
        first = subgroupBroadcastFirst(base_) + offset_;                          \
    }
