// The delta passes' own descriptor set (shared_layout.h, "mesh deltas"): the heaps, their shadows as
// last reported, and the record lists. Same rules as structure/frame.glsl: no waiting, bounded loops.
#ifndef VKMESH_HASH32
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require   // shared_layout.h declares 64-bit constants
#endif
#extension GL_KHR_shader_subgroup_basic : require

#include "shared_layout.h"

layout(std430, set = 0, binding = DELTA_BINDING_COUNTERS) readonly buffer CountersBuffer { Counters counters; };
layout(std430, set = 0, binding = DELTA_BINDING_VERTICES) readonly buffer Vertices { Vertex vertices[]; };
layout(std430, set = 0, binding = DELTA_BINDING_PREV_VERTICES) buffer PrevVertices { Vertex prevVertices[]; };
layout(std430, set = 0, binding = DELTA_BINDING_CHUNKS) readonly buffer ChunkTriangles { uint chunkTriangles[]; };
layout(std430, set = 0, binding = DELTA_BINDING_PREV_CHUNKS) buffer PrevChunkTriangles { uint prevChunkTriangles[]; };
layout(std430, set = 0, binding = DELTA_BINDING_STATE) coherent buffer DeltaStateBuffer { DeltaState deltaState; };
layout(std430, set = 0, binding = DELTA_BINDING_VERTEX_RECORDS) writeonly buffer VertexRecords { DeltaVertexRecord vertexRecords[]; };
layout(std430, set = 0, binding = DELTA_BINDING_TRIANGLE_RECORDS) writeonly buffer TriangleRecords { DeltaTriangleRecord triangleRecords[]; };

const uint DELTA_NONE = 0xFFFFFFFFu;
