#version 460
// One workgroup per block cull_view_blocks listed, VIEW_CUBES_PER_INVOCATION cubes per invocation: the chunks of
// its cubes that hold triangles are listed for emit_view_triangles (a chunk belongs to one cube: listed once).
#extension GL_GOOGLE_include_directive : require
#include "model_view.glsl"

layout(local_size_x = WG_VIEW_BLOCK) in;

void main() {
    uint block = viewBlocks[gl_WorkGroupID.x];
    uint first = (block * VOXELS_PER_BLOCK + gl_LocalInvocationID.x * VIEW_CUBES_PER_INVOCATION) / 4u;
    uvec4 states[2] = uvec4[2](cubeStates[first], cubeStates[first + 1u]);
    uint count = 0u;
    for (uint i = 0u; i < VIEW_CUBES_PER_INVOCATION; ++i) count += (states[i / 4u][i % 4u] >> CUBE_CHUNK_SHIFT) != 0u ? 1u : 0u;
    uint at;
    APPEND_PER_SUBGROUP(viewState.chunkCount, count, at);
    // The emit pass's workgroups cover every chunk listed (the largest end any subgroup reached).
    uint end = subgroupMax(at + count);
    if (subgroupElect()) atomicMax(viewState.chunkDispatch[0], (end + WG_LIST - 1u) / WG_LIST);
    for (uint i = 0u; i < VIEW_CUBES_PER_INVOCATION; ++i) {
        uint chunk = states[i / 4u][i % 4u] >> CUBE_CHUNK_SHIFT;   // chunk index + 1
        if (chunk != 0u) viewChunks[at++] = chunk - 1u;
    }
}
