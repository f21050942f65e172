#version 460
// Incremental mesh: marks the cubes whose type may change around the corners of the dirty blocks that changed,
// before the retype list is collected. One invocation per mask word of each dirty block (its 32 corners: 4 rows
// along x of one z layer):
//  - the corners fusion flipped (sign or observed state: cornerFlips, structure/frame_lists.glsl), taken and
//    cleared;
//  - with refinement (docs/REFINEMENT.md), the corners whose meshing sign changed: every corner's is re-decided
//    from the masks of the TSDF that fusion keeps (raw sign, near, observed: no sdf or weight is read); the word's
//    window is a few shifts and ors of the mask words of the block and of its neighbours (from the neighbour
//    cache), and only the corners that may flip are decided bit by bit (swDecideWord, retype/sign_window.h, the
//    same function as refinedCornerInside in src/core/refinement.cpp), and a changed word is stored.
// The 8 cubes around each such corner are marked for retyping: in this block or, for corners on its low faces, in
// the blocks behind.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"

#define SIGN_WINDOW_WORDS(b, layer, rowHalf) ((b) == NO_BLOCK ? uvec4(0u) : meshSignGroups[(b) * MASK_WORDS + 2u * (layer) + (rowHalf)])
#define SIGN_WINDOW_NEIGHBOR(b, ox, oy, oz) cachedNeighbor(b, ivec3(ox, oy, oz))
#include "retype/sign_window.h"

layout(local_size_x = WG_LIST) in;

// Sets the retype bits `bits` of word (layer, rowHalf) of the block at `offset` from `block` (if it exists).
void markCubes(uint block, ivec3 offset, uint layer, uint rowHalf, uint bits) {
    if (bits == 0u) return;
    uint b = offset == ivec3(0) ? block : cachedNeighbor(block, offset);
    if (b != NO_BLOCK) atomicOr(retypeMask[b * MASK_WORDS + 2u * layer + rowHalf], bits);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint evaluated = 0u;
    if (i < counters.dirtyCount * MASK_WORDS) {
        uint block = dirtyList[i / MASK_WORDS], word = i % MASK_WORDS;
        uint changed = cornerFlips[block * MASK_WORDS + word];
        if (changed != 0u) cornerFlips[block * MASK_WORDS + word] = 0u;
        if (volumeRefines()) {
            uvec4 own = meshSignGroups[block * MASK_WORDS + word];   // its meshing signs and masks
            uint signs = swDecideWord(block, word, own, evaluated);
            uint signChanged = signs ^ own[MESH_SIGN_MESHING];
            if (signChanged != 0u) meshSigns[block * MESH_SIGN_WORDS + MESH_SIGN_GROUP * word + MESH_SIGN_MESHING] = signs;   // this invocation's word only
            changed |= signChanged;
        }
        if (changed != 0u) {
            // The cubes corner - o, o in {0,1}^3: one row along y lower (oy), one column along x lower (ox: corners
            // at x = 0 reach x = 7 of the block at -x), one layer lower (oz: layer 0 reaches layer 7 at -z).
            uint z = word / 2u, rh = word % 2u;
            for (uint oz = 0u; oz < 2u; ++oz) {
                int bz = oz == 1u && z == 0u ? -1 : 0;
                uint layer = (z + BLOCK_SIDE - oz) % BLOCK_SIDE;
                for (uint ox = 0u; ox < 2u; ++ox) {
                    uint same = ox == 1u ? (changed >> 1) & 0x7F7F7F7Fu : changed;
                    uint edge = ox == 1u ? (changed & 0x01010101u) << 7 : 0u;   // into the block at -x
                    markCubes(block, ivec3(0, 0, bz), layer, rh, same);
                    markCubes(block, ivec3(-1, 0, bz), layer, rh, edge);
                    // oy = 1: rows 1..3 of the word move down in it; its row 0 becomes row 3 of the other word (rh = 1)
                    // or row 7 of the block at -y (rh = 0).
                    markCubes(block, ivec3(0, 0, bz), layer, rh, same >> 8);
                    markCubes(block, ivec3(-1, 0, bz), layer, rh, edge >> 8);
                    int by = rh == 0u ? -1 : 0;
                    markCubes(block, ivec3(0, by, bz), layer, 1u - rh, (same & 0xFFu) << 24);
                    markCubes(block, ivec3(-1, by, bz), layer, 1u - rh, (edge & 0xFFu) << 24);
                }
            }
        }
    }
    ADD_COUNTER(signCornerCount, evaluated);
}
