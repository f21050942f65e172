// The marching-cubes tables (src/core/marching_cubes.h) in the word layout of shared_layout.h
// (MC_TRIANGLE_WORDS_OFFSET), uploaded once.
#ifndef VKMESH_MC_TABLES_GLSL
#define VKMESH_MC_TABLES_GLSL
#include "structure/frame.glsl"

// A uniform buffer (5 KiB, std140: 4 words per vec4 slot), not a storage buffer: the mesh passes that read it
// already use most of their storage-buffer budget (vk::kMaxStorageBuffersPerPipeline).
layout(std140, set = 0, binding = BINDING_MC_TABLES) uniform McTables { uvec4 mcTableWords[MC_TABLE_WORDS / 4u]; };

uint mcTableWord(uint i) { return mcTableWords[i >> 2][i & 3u]; }
uint edgeMaskOf(uint type) { return mcTableWord(type) & 0xFFFFu; }
uint triangleCountOf(uint type) { return mcTableWord(type) >> 16; }
uint triangleEdge(uint type, uint i) {
    uint word = mcTableWord(MC_TRIANGLE_WORDS_OFFSET + type * 4u + i / 4u);
    return (word >> ((i % 4u) * 8u)) & 0xFFu;
}
#endif
