#version 460
// One invocation per chunk list_view_chunks listed: its triangles appended to the index list, and the draw's
// index count raised. With a createdBefore, only the triangles whose three vertices are older (the older map).
#extension GL_GOOGLE_include_directive : require
#include "model_view.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint base = 0u, mask = 0u;   // bit t: triangle slot t of the chunk holds a triangle
    if (i < viewState.chunkCount) {
        base = viewChunks[i] * CHUNK_WORDS;
        for (uint t = 0u; t < TRIANGLES_PER_CHUNK; ++t) {
            uint a = chunkTriangles[base + 3u * t];
            if (a == INVALID_INDEX) continue;
            if (pc.createdBefore != 0xFFFFFFFFu &&
                (vertices[a].createdFrame >= pc.createdBefore || vertices[chunkTriangles[base + 3u * t + 1u]].createdFrame >= pc.createdBefore ||
                 vertices[chunkTriangles[base + 3u * t + 2u]].createdFrame >= pc.createdBefore))
                continue;
            mask |= 1u << t;
        }
    }
    uint at;
    APPEND_PER_SUBGROUP(viewState.draw[0], 3u * bitCount(mask), at);
    for (uint t = 0u; t < TRIANGLES_PER_CHUNK; ++t) {
        if ((mask & (1u << t)) == 0u) continue;
        for (uint j = 0u; j < 3u; ++j) viewIndices[at + j] = chunkTriangles[base + 3u * t + j];
        at += 3u;
    }
}
