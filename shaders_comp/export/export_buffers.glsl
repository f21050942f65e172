// The compacted, draw-ready mesh (src/gpu/export_mesh_stage.h): dense vertices and a triangle index list,
// and the heap index -> compacted index remap used while compacting.
#ifndef VKMESH_EXPORT_BUFFERS_GLSL
#define VKMESH_EXPORT_BUFFERS_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_EXPORT_VERTICES) buffer ExportVertices { Vertex exportVertices[]; };
layout(std430, set = 0, binding = BINDING_EXPORT_INDICES) buffer ExportIndices { uint exportIndices[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_REMAP) buffer VertexRemap { uint vertexRemap[]; };
#endif
