#version 460
// Export, pass 2: every live triangle of every cube of the listed blocks, with its vertices' dense
// indices, into one index buffer. One workgroup per block.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = WG_BLOCK) in;

void main() {
    uint block = blockList[gl_WorkGroupID.x];
    for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        uint state = cubeState[block * VOXELS_PER_BLOCK + gl_LocalInvocationIndex + k * WG_BLOCK];
        uint chunk = state >> CUBE_CHUNK_SHIFT;
        uint count = chunk == 0u ? 0u : (mcTables[state & CUBE_TYPE_MASK] >> 16);
        for (uint t = 0u; t < count; ++t) {
            uint base = (chunk - 1u) * CHUNK_WORDS + 3u * t;
            if (chunkTriangles[base] == INVALID_INDEX) continue;
            uint at = atomicAdd(counters.exportTriangles, 1u);
            if (at >= params.exportTriangleCapacity) continue;   // counted: the host grows the buffer and re-runs
            for (uint j = 0u; j < 3u; ++j) exportIndices[3u * at + j] = vertexRemap[chunkTriangles[base + j]];
        }
    }
}
