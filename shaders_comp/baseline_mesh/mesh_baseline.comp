#version 460
// The paper's baseline (Chisel-style) mesh: marching cubes over every cube of every listed block, each
// cube writing its triangles with 3 vertices of their own (no sharing). One workgroup per block.
// A cube is the one whose corner 0 is the block's corner (x, y, z); corners with a coordinate of 8 lie
// in a neighbouring block, found once per workgroup through the hash.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"
#include "structure/mc_tables.glsl"
#include "structure/cube_access.glsl"

// The triangle soup: 3 vertices of its own per triangle (xyz, w unused), counted in Counters::meshVertices.
layout(std430, set = 0, binding = BINDING_MESH_VERTICES) buffer MeshVertices { vec4 meshVertices[]; };

layout(local_size_x = WG_BLOCK) in;


shared uint neighbour[8];   // the workgroup's block and its 7 +x/+y/+z neighbours, looked up once

void main() {
    uint block = blockList[gl_WorkGroupID.x];
    if (gl_LocalInvocationIndex < 8u) {
        uint i = gl_LocalInvocationIndex;
        neighbour[i] = i == 0u ? block : findBlock(blockCoords[block].xyz + ivec3(cornerOffset(i)));
    }
    barrier();
    CubeRef r;
    [[unroll]] for (uint i = 0u; i < 8u; ++i) r.nb[i] = neighbour[i];
    r.origin = blockCoords[block].xyz * int(BLOCK_SIDE);

    uint dropped = 0u;
    for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        r.cube = cubeOfLocal(gl_LocalInvocationIndex + k * WG_BLOCK);
        float d[8];
        bool present[8];
        bool observed;
        uint type = loadCube(r, d, present, observed);
        uint triangles = observed ? triangleCountOf(type) : 0u;
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
                meshVertices[base + t] = vec4(edgeVertexPosition(r, lo, e / 4u, edgeCrossing(cornerValue(d, lo), cornerValue(d, hi), false)), 1.0);
            }
        }
    }
    ADD_COUNTER(meshVerticesDropped, dropped);
}
