#version 460
// The paper's baseline (Chisel-style) mesh: marching cubes over every cube of every listed block, each
// cube writing its triangles with 3 vertices of their own (no sharing). One workgroup per block.
// A cube is the one whose corner 0 is the block's corner (x, y, z); corners with a coordinate of 8 lie
// in a neighbouring block, found once per workgroup through the hash.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = WG_BLOCK) in;

shared uint neighbour[8];   // block index of the block at offset (i&1, i>>1&1, i>>2&1), or NO_BLOCK
shared ivec3 blockOrigin;

uvec3 cornerOffset(uint c) { return uvec3(c & 1u, (c >> 1) & 1u, (c >> 2) & 1u); }

// Edge e of the cube (axis-major numbering, see src/core/marching_cubes.h): its low corner and axis.
uint edgeLowCorner(uint e) {
    uint axis = e / 4u, k = e % 4u;
    uvec3 o = axis == 0u ? uvec3(0u, k & 1u, k >> 1) : (axis == 1u ? uvec3(k & 1u, 0u, k >> 1) : uvec3(k & 1u, k >> 1, 0u));
    return o.x | (o.y << 1) | (o.z << 2);
}

uint triangleEdge(uint type, uint i) {
    uint word = mcTables[MC_TRIANGLE_WORDS_OFFSET + type * 4u + i / 4u];
    return (word >> ((i % 4u) * 8u)) & 0xFFu;
}

void main() {
    uint block = blockList[gl_WorkGroupID.x];
    if (gl_LocalInvocationIndex < 8u) {
        ivec3 coord = blockCoords[block].xyz;
        uint i = gl_LocalInvocationIndex;
        neighbour[i] = i == 0u ? block : findBlock(coord + ivec3(cornerOffset(i)));
        if (i == 0u) blockOrigin = coord * int(BLOCK_SIDE);
    }
    barrier();

    uint dropped = 0u;
    for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        uint local = gl_LocalInvocationIndex + k * WG_BLOCK;
        uvec3 cube = uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
        float d[8];
        bool observed = true;
        uint type = 0u;
        for (uint c = 0u; c < 8u; ++c) {
            uvec3 g = cube + cornerOffset(c);
            uvec3 wrap = g / BLOCK_SIDE;   // 1 on an axis where the corner lies in the next block
            uint nb = neighbour[wrap.x | (wrap.y << 1) | (wrap.z << 2)];
            d[c] = 0.0;
            if (nb == NO_BLOCK) { observed = false; continue; }
            uint v = voxelIndex(nb, g % BLOCK_SIDE);
            if (voxelWeight[v] < params.minMeshWeight) observed = false;
            d[c] = voxelSdf[v];
            if (d[c] < 0.0) type |= 1u << c;
        }
        uint triangles = observed ? (mcTables[type] >> 16) : 0u;
        uint vertexCount = 3u * triangles;

        // One atomic per subgroup reserves room for all of its cubes' vertices.
        uint offset = subgroupExclusiveAdd(vertexCount);
        uint total = subgroupAdd(vertexCount);
        uint base = 0u;
        if (subgroupElect() && total != 0u) base = atomicAdd(counters.meshVertices, total);
        base = subgroupBroadcastFirst(base) + offset;

        if (vertexCount != 0u && base + vertexCount > params.meshVertexCapacity) {
            dropped += vertexCount;
        } else {
            for (uint t = 0u; t < vertexCount; ++t) {
                uint e = triangleEdge(type, t);
                uint lo = edgeLowCorner(e);
                uint hi = lo | (1u << (e / 4u));
                precise float s = d[lo] / (d[lo] - d[hi]);
                precise vec3 p = vec3(blockOrigin + ivec3(cube + cornerOffset(lo)));
                p[e / 4u] += s;
                meshVertices[base + t] = vec4(p * params.voxelSize, 1.0);
            }
        }
    }
    ADD_COUNTER(meshVerticesDropped, dropped);
}
