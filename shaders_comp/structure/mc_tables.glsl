// The marching-cubes tables (src/core/marching_cubes.h) in the word layout of shared_layout.h
// (MC_TRIANGLE_WORDS_OFFSET), uploaded once.
#ifndef VKMESH_MC_TABLES_GLSL
#define VKMESH_MC_TABLES_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_MC_TABLES) readonly buffer McTables { uint mcTables[]; };

uint edgeMaskOf(uint type) { return mcTables[type] & 0xFFFFu; }
uint triangleCountOf(uint type) { return mcTables[type] >> 16; }
uint triangleEdge(uint type, uint i) {
    uint word = mcTables[MC_TRIANGLE_WORDS_OFFSET + type * 4u + i / 4u];
    return (word >> ((i % 4u) * 8u)) & 0xFFu;
}
#endif
