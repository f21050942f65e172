#version 460
// One invocation before the listing: an empty draw and empty lists (the passes raise the counts and dispatches).
#extension GL_GOOGLE_include_directive : require
#include "model_view.glsl"

layout(local_size_x = 1) in;

void main() {
    viewState.draw[0] = 0u;   // indexCount, raised by emit_view_triangles
    viewState.draw[1] = 1u;   // instanceCount
    viewState.draw[2] = 0u;   // firstIndex
    viewState.draw[3] = 0u;   // vertexOffset
    viewState.draw[4] = 0u;   // firstInstance
    viewState.chunkCount = 0u;
    for (uint i = 0u; i < 3u; ++i) {
        viewState.blockDispatch[i] = i == 0u ? 0u : 1u;
        viewState.chunkDispatch[i] = i == 0u ? 0u : 1u;
    }
}
