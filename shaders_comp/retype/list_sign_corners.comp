#version 460
// Incremental mesh with refinement (docs/REFINEMENT.md): lists the corners whose meshing sign may have changed,
// for decide_mesh_signs. A corner's sign reads the signs and observed states of the 3x3x3 corners around it
// and its own |d| < epsilon. Fusion and recycling mark the 8 cubes around every corner whose sign or observed
// state changed, and the corners within one of such a corner are exactly the corners of those 8 cubes; fusion
// also flags the corners whose |d| < epsilon changed (nearChangeWord). So a corner is listed when it is
// flagged, or when one of the 8 cubes it is a corner of (corner - o, o in {0,1}^3, in its block or the
// blocks behind) is marked; the flags are cleared. One invocation per retype-mask word of the dirty blocks (its
// 32 corners: 4 rows along x of one z layer); the list is the retype list, free until collect_retype. Corners
// past its capacity are decided here.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "retype/mesh_signs.glsl"

layout(local_size_x = WG_LIST) in;

uint behind[8];   // the block at offset -(o & 1, o >> 1 & 1, o >> 2 & 1) (the cube offsets), from the cache

uint markWord(uint b, uint layer, uint rowHalf) {
    return b == NO_BLOCK ? 0u : retypeMask[b * MASK_WORDS + 2u * layer + rowHalf];
}

// The marks of the cubes one row lower (oy = 1) or in the same row (oy = 0) as the corners of rows 4 rowHalf ..
// 4 rowHalf + 3 of a z layer, from the cubes of layer `layer` of the block at x / z offset bx / bz (0 or 1).
uint rowsWord(uint bx, uint bz, uint layer, uint rowHalf, uint oy) {
    uint b = behind[bx | (bz << 2)];
    uint here = markWord(b, layer, rowHalf);
    if (oy == 0u) return here;
    uint lower = rowHalf == 1u ? markWord(b, layer, 0u) >> 24 : markWord(behind[bx | 2u | (bz << 2)], layer, 1u) >> 24;
    return (here << 8) | lower;
}

// Bit i set: corner (i % 8, 4 rowHalf + i / 8, z) of the block is a corner of a marked cube.
uint cornersOfMarkedCubes(uint word) {
    uint z = word / 2u, rowHalf = word % 2u;
    uint corners = 0u;
    for (uint oz = 0u; oz < 2u; ++oz) {
        uint bz = oz == 1u && z == 0u ? 1u : 0u;
        uint layer = oz == 0u ? z : (z == 0u ? BLOCK_SIDE - 1u : z - 1u);
        for (uint oy = 0u; oy < 2u; ++oy) {
            uint same = rowsWord(0u, bz, layer, rowHalf, oy);
            uint lower = rowsWord(1u, bz, layer, rowHalf, oy);   // x = 7 of the block behind in x, for corners at x = 0
            corners |= same | ((same << 1) & 0xFEFEFEFEu) | ((lower >> 7) & 0x01010101u);
        }
    }
    return corners;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    bool valid = i < counters.dirtyCount * MASK_WORDS;
    uint block = valid ? dirtyList[i / MASK_WORDS] : NO_BLOCK;
    uint word = i % MASK_WORDS;
    uint bits = 0u;
    if (valid) {
        for (uint o = 0u; o < 8u; ++o)
            behind[o] = o == 0u ? block : cachedNeighbor(block, -ivec3(cornerOffset(o)));
        bits = cornersOfMarkedCubes(word) | atomicExchange(meshSigns[nearChangeWord(block, word * 32u)], 0u);
    }
    // One atomic per subgroup (every invocation gets here: no early return above).
    uint n = bitCount(bits);
    uint offset = subgroupExclusiveAdd(n), total = subgroupAdd(n);
    uint base = 0u;
    if (subgroupElect() && total != 0u) base = atomicAdd(counters.signCornerCount, total);
    uint at = subgroupBroadcastFirst(base) + offset;
    for (uint k = 0u; k < 32u && bits != 0u; ++k, ++at) {   // over the set bits
        uint local = word * 32u + findLSB(bits);
        bits &= bits - 1u;
        if (at < params.retypeCapacity) retypeList[at] = block * VOXELS_PER_BLOCK + local;
        else decideMeshSign(block, local);
    }
}
