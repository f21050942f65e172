// Marching cubes on the hashed grid. A cube (block, local x y z) reads its 8 corners and finds the owner
// slot of each of its 12 edges in its own block or its +x/+y/+z neighbours, collected in a CubeRef.
// Conventions: src/core/marching_cubes.h (corner i at (i&1, i>>1&1, i>>2&1); edges axis-major).
#ifndef VKMESH_CUBE_ACCESS_GLSL
#define VKMESH_CUBE_ACCESS_GLSL
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/mc_tables.glsl"
#include "structure/frame_lists.glsl"

struct CubeRef {
    uint nb[8];       // block at offset cornerOffset(i) from the cube's block (nb[0]), NO_BLOCK if absent
    ivec3 origin;     // global grid index of the block's corner 0 (block coordinate * 8)
    uvec3 cube;       // the cube's position in its block
};

uvec3 cornerOffset(uint c) { return uvec3(c & 1u, (c >> 1) & 1u, (c >> 2) & 1u); }

uvec3 cubeOfLocal(uint local) {
    return uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
}

uint localOfCube(uvec3 c) { return (c.z * BLOCK_SIDE + c.y) * BLOCK_SIDE + c.x; }

// A cube of a dirty block on its own: the neighbours it can reach (only on the axes where it sits at the
// block's far side), from the block's neighbour cache (frame_lists.glsl). The cubes of the retype list are
// in dirty blocks.
CubeRef cubeRef(uint block, uint local) {
    CubeRef r;
    r.cube = cubeOfLocal(local);
    r.origin = blockCoords[block].xyz * int(BLOCK_SIDE);
    uvec3 far = uvec3(equal(r.cube, uvec3(BLOCK_SIDE - 1u)));
    r.nb[0] = block;
    [[unroll]] for (uint i = 1u; i < 8u; ++i) {
        uvec3 o = cornerOffset(i);
        r.nb[i] = all(lessThanEqual(o, far)) ? cachedNeighbor(block, ivec3(o)) : NO_BLOCK;
    }
    return r;
}

// The same for a cube of any block: a block that is not dirty this frame (a vertex created this frame on an
// edge owned by a clean block) has no valid cache, and its neighbours are looked up in the hash.
CubeRef cubeRefAnyBlock(uint block, uint local) {
    if (blockDirty(block)) return cubeRef(block, local);
    CubeRef r;
    r.cube = cubeOfLocal(local);
    ivec3 coord = blockCoords[block].xyz;
    r.origin = coord * int(BLOCK_SIDE);
    uvec3 far = uvec3(equal(r.cube, uvec3(BLOCK_SIDE - 1u)));
    r.nb[0] = block;
    [[unroll]] for (uint i = 1u; i < 8u; ++i) {
        uvec3 o = cornerOffset(i);
        r.nb[i] = all(lessThanEqual(o, far)) ? findBlock(coord + ivec3(o)) : NO_BLOCK;
    }
    return r;
}

// A position up to 8 (inclusive) on each axis from the cube's block: which block holds it and where.
// Selects rather than r.nb[index]: llvmpipe turns a dynamically indexed local array into a ladder of branches
// or a per-lane scratch access, which cost claim and triangulate more than all their buffer loads.
uint blockHolding(CubeRef r, uvec3 g, out uvec3 local) {
    bvec3 wrap = greaterThanEqual(g, uvec3(BLOCK_SIDE));
    local = g % BLOCK_SIDE;
    uint x0 = wrap.x ? r.nb[1] : r.nb[0], x1 = wrap.x ? r.nb[3] : r.nb[2];
    uint x2 = wrap.x ? r.nb[5] : r.nb[4], x3 = wrap.x ? r.nb[7] : r.nb[6];
    uint y0 = wrap.y ? x1 : x0, y1 = wrap.y ? x3 : x2;
    return wrap.z ? y1 : y0;
}

// d[c] for a c known only at run time, by selects (as blockHolding).
float cornerValue(float d[8], uint c) {
    bool x = (c & 1u) != 0u, y = (c & 2u) != 0u;
    float z0 = y ? (x ? d[3] : d[2]) : (x ? d[1] : d[0]);
    float z1 = y ? (x ? d[7] : d[6]) : (x ? d[5] : d[4]);
    return (c & 4u) != 0u ? z1 : z0;
}

// The 8 corner values of a cube (present[c]: the corner's block exists) and its MC type; `observed` is
// false (type 0) unless every corner's block exists and every corner has weight >= minMeshWeight.
// (Reading a row's two corners as one four-corner element, block_store.glsl, where both lie in it took
// move_vertices 1.31 -> 1.59 ms on the synthetic room: the selects of the components and the fourth corner's own
// reads cost more than the loads they save.)
uint loadCube(CubeRef r, out float d[8], out bool present[8], out bool observed) {
    uint type = 0u;
    observed = true;
    [[unroll]] for (uint c = 0u; c < 8u; ++c) {
        uvec3 local;
        uint nb = blockHolding(r, r.cube + cornerOffset(c), local);
        d[c] = 0.0;
        present[c] = nb != NO_BLOCK;
        if (nb == NO_BLOCK) { observed = false; continue; }
        uint v = voxelIndex(nb, local);
        if (voxelWeight[v] < params.minMeshWeight) observed = false;
        d[c] = cornerSdf(v);
        if (d[c] < 0.0) type |= 1u << c;
    }
    return observed ? type : 0u;
}

// Edge e of a cube (axis-major numbering): its low corner; its high corner is low | (1 << axis).
uint edgeLowCorner(uint e) {
    uint axis = e / 4u, k = e % 4u;
    uvec3 o = axis == 0u ? uvec3(0u, k & 1u, k >> 1) : (axis == 1u ? uvec3(k & 1u, 0u, k >> 1) : uvec3(k & 1u, k >> 1, 0u));
    return o.x | (o.y << 1) | (o.z << 2);
}

// Index into edgeVertex of the slot holding edge e of the cube: the slot (axis of e) of the cube at the
// edge's low corner, which may be in a neighbouring block. NO_BLOCK if that block does not exist.
uint edgeSlot(CubeRef r, uint e) {
    uvec3 local;
    uint nb = blockHolding(r, r.cube + cornerOffset(edgeLowCorner(e)), local);
    if (nb == NO_BLOCK) return NO_BLOCK;
    return (nb * VOXELS_PER_BLOCK + localOfCube(local)) * 3u + e / 4u;
}

// Where the vertex of an edge sits along it, s from the low corner: the zero crossing interpolated from the
// corners' values. No vertex may sit on a corner, so that no two vertices coincide (docs/REFINEMENT.md,
// "Vertices"); a corner's distance is exactly 0 whenever its integer step sum is (shared_layout.h, "A TSDF
// corner"), which is common enough that the unrefined mesh and the baseline need this too:
// - in a refined mesh (`refined`), an edge whose corners share a raw sign carries a vertex only because refinement flipped one of its corners
//   for meshing; the crossing extrapolated from its values lies beyond the flipped corner, and the vertex stops
//   1/FLIPPED_EDGE_MARGIN_INVERSE of the edge before that corner. Up to two such edges meet at a flipped
//   corner: clamped onto the corner itself their vertices would share its position;
// - any other edge keeps s in [1/REFINED_EDGE_MARGIN_INVERSE, 1 - 1/REFINED_EDGE_MARGIN_INVERSE], so that
//   a crossing a hair from a corner (or on it: d = 0) is not rounded onto the corner. That moves a vertex by
//   at most 1/1024 of a voxel.
// Every vertex then lies strictly inside its own edge, and edges share no inner point. Equal values (only on a
// flipped edge): the midpoint. Written out so that the CPU reference (edgeCrossing in src/core/refinement.h)
// reproduces it bit for bit.
float edgeCrossing(float dLo, float dHi, bool refined) {
    if (dLo == dHi) return 0.5;
    uint inverse = refined && (dLo < 0.0) == (dHi < 0.0) ? FLIPPED_EDGE_MARGIN_INVERSE : REFINED_EDGE_MARGIN_INVERSE;
    float margin = 1.0 / float(inverse);
    precise float s = clamp(dLo / (dLo - dHi), margin, 1.0 - margin);
    return s;
}

// Position of the vertex at s (edgeCrossing) on the edge from corner `lo` along `axis` of the cube, in grid
// units, then metres. Written out so the CPU reference reproduces it bit for bit; the baseline and the
// shared-vertex mesh use this one function, so their vertices coincide exactly where s does.
vec3 edgeVertexPosition(CubeRef r, uint lo, uint axis, float s) {
    precise vec3 p = vec3(r.origin + ivec3(r.cube + cornerOffset(lo)));
    p += mix(vec3(0.0), vec3(s), equal(uvec3(axis), uvec3(0u, 1u, 2u)));   // p[axis] += s: + 0.0 leaves the others exact
    precise vec3 world = p * params.voxelSize;
    return world;
}

// ---- refinement, flips decided per corner (docs/REFINEMENT.md) ------------------------------------------------
// Each corner's meshing sign is decided once and stored (decide_mesh_signs, from the masks of the TSDF:
// retype/sign_window.h; refinedCornerInside in src/core/refinement.cpp is the CPU specification).

// The type a listed cube is built with (claim and triangulate): its MC type (loadCube: 0 unless observed) or, with
// refinement, the MC type of its corners' stored meshing signs (decide_mesh_signs), 0 unless observed. A refined
// volume reads no sdf or weight for it: `observed` is the corners' OBSERVED mask bits (weight >= minMeshWeight,
// kept exact beside the TSDF), and the 8 corners lie in 4 rows along x whose two corners share a mask word unless
// the cube sits at its block's +x side, so most cubes read 4 words of each mask (8 loads where loadCube and the
// signs took 24; claim -0.1 ms on the synthetic room).
uint listedCubeType(CubeRef r) {
    if (!volumeRefines()) {
        float d[8];
        bool present[8];
        bool observed;
        return loadCube(r, d, present, observed);
    }
    uint type = 0u;
    for (uint row = 0u; row < 4u; ++row) {   // row = dy + 2 dz: corners 2 row (dx = 0) and 2 row + 1 (dx = 1)
        uvec3 local;
        uint nb = blockHolding(r, r.cube + uvec3(0u, row & 1u, row >> 1), local);
        if (nb == NO_BLOCK) return 0u;
        uint at = localOfCube(local), bit = at % 32u;
        uvec4 group = meshSignGroups[meshSignGroup(nb, at)];   // one load for both
        uint signs = group[MESH_SIGN_MESHING], seen = group[MESH_SIGN_OBSERVED];
        uint pair = (signs >> bit) & 1u, seenPair = (seen >> bit) & 1u;
        if (local.x + 1u < BLOCK_SIDE) {   // the dx = 1 corner is the next bit of the same words
            pair |= ((signs >> (bit + 1u)) & 1u) << 1;
            seenPair |= ((seen >> (bit + 1u)) & 1u) << 1;
        } else {                           // at x = 0 of the block at +x
            uint nx = blockHolding(r, r.cube + uvec3(1u, row & 1u, row >> 1), local);
            if (nx == NO_BLOCK) return 0u;
            uint ax = localOfCube(local);
            uvec4 next = meshSignGroups[meshSignGroup(nx, ax)];
            pair |= ((next[MESH_SIGN_MESHING] >> (ax % 32u)) & 1u) << 1;
            seenPair |= ((next[MESH_SIGN_OBSERVED] >> (ax % 32u)) & 1u) << 1;
        }
        if (seenPair != 3u) return 0u;
        type |= pair << (2u * row);
    }
    return type;
}
#endif
