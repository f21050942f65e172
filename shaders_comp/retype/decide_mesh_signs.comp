#version 460
// Incremental mesh: marks the cubes whose type may change around the corners of the dirty blocks that changed,
// before the retype list is collected. Each mask word of a dirty block (its 32 corners: 4 rows along x of one z layer)
// that has work (main) is decided by one invocation of its workgroup:
//  - the corners fusion flipped (sign or observed state: cornerFlips, structure/frame_lists.glsl), taken and
//    cleared;
//  - with refinement (docs/REFINEMENT.md), the corners whose meshing sign changed: every corner's is re-decided
//    from the masks of the TSDF that fusion keeps (raw sign, near, observed: no sdf or weight is read); the word's
//    window is a few shifts and ors of the mask words of the block and of its neighbours (from the neighbour
//    cache), and only the corners that may flip are decided bit by bit (swDecideWord, retype/sign_window.h, the
//    same function as refinedCornerInside in src/core/refinement.cpp), and a changed word is stored.
// The 8 cubes around each such corner are marked for retyping (in this block or, for corners on its low faces, in
// the blocks behind): with refinement, only those whose type the change can alter (cubeWindow). A cube with a corner
// that is not observed has type 0, as has one whose corners are all outside; most observed flips happen in free
// space in front of the surface and most sign changes at the edge of what is observed, and the cubes around them
// were most of the retype list, where mesh_claim classified them to find their type unchanged.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"

#define SIGN_WINDOW_WORDS(b, layer, rowHalf) ((b) == NO_BLOCK ? uvec4(0u) : meshSignGroups[(b) * MASK_WORDS + 2u * (layer) + (rowHalf)])
#define SIGN_WINDOW_NEIGHBOR(b, ox, oy, oz) cachedNeighbor(b, ivec3(ox, oy, oz))
#include "retype/sign_window.h"

layout(local_size_x = WG_LIST / DECIDE_WORDS_PER_INVOCATION) in;

// The words of this workgroup's WG_LIST that have work (activeWords: dirty-word index; activeFlips: their flips),
// listed by the invocations that checked them. Most words of the dirty blocks have none: on the synthetic room ~21 %
// have near corners, flips or meshing signs that differ from the raw ones, and llvmpipe runs a body under a mask for
// every lane whether it has work or not, so the decision costs per invocation that reaches it, not per word decided.
shared uint activeWords[WG_LIST];
shared uint activeFlips[WG_LIST];
shared uint activeCount;

// Sets the retype bits `bits` of word (layer, rowHalf) of the block at `offset` from `block` (if it exists).
void markCubes(uint block, ivec3 offset, uint layer, uint rowHalf, uint bits) {
    if (bits == 0u) return;
    uint b = offset == ivec3(0) ? block : cachedNeighbor(block, offset);
    if (b != NO_BLOCK) atomicOr(retypeMask[b * MASK_WORDS + 2u * layer + rowHalf], bits);
}

// For the word's corners at `need`, per cube offset o = (ox, oy, oz) (cube corner - o, index ox + 2 oy + 4 oz): x,
// whether the cube has a corner that may be inside for meshing (raw sign inside, or near: only a near corner's
// meshing sign differs from its raw one); y, whether its 8 corners are all observed. From the 27 words of the raw,
// near and observed masks around the word (sign_window.h, exact at `need`), reusing the 6 edge neighbours' groups
// where the sign decision read them (`faces`). Fusion wrote these masks; nothing in this dispatch changes them, so
// the marks do not depend on the order in which the words are decided (the meshing signs themselves would).
uvec2 mayBeInsideObserved(uvec4 group) { return uvec2(group[MESH_SIGN_RAW] | group[MESH_SIGN_NEAR], group[MESH_SIGN_OBSERVED]); }

void cubeWindow(uint block, uint word, uvec4 own, uint need, bool faces, uvec4 left, uvec4 right, uvec4 other, uvec4 beyond,
                uvec4 lower, uvec4 upper, out uvec2 w[8]) {
    uint z = word / 2u, rh = word % 2u;
    uvec2 p0, p1, p2, p3, p4, p5, p6, p7, p8, p9, p10, p11, p12, p13, p14, p15, p16, p17, p18, p19, p20, p21, p22, p23,
        p24, p25, p26;
    const uvec2 none = uvec2(0u);
    uint have = faces ? 1u : 0u;
    swLayer(block, z, rh, -1, need, have, mayBeInsideObserved(lower), none, none, none, none, true, p0, p1, p2, p3, p4, p5, p6, p7,
            p8);
    swLayer(block, z, rh, 0, need, faces ? 31u : 1u, mayBeInsideObserved(own), mayBeInsideObserved(other), mayBeInsideObserved(beyond),
            mayBeInsideObserved(left), mayBeInsideObserved(right), true, p9, p10, p11, p12, p13, p14, p15, p16, p17);
    swLayer(block, z, rh, 1, need, have, mayBeInsideObserved(upper), none, none, none, none, true, p18, p19, p20, p21, p22, p23, p24,
            p25, p26);
    // Per layer (a: dz = -1, b: 0, c: +1), the 2 x 2 corners of cube offset (ox, oy): dx in {-ox, 1 - ox}, dy likewise.
    uvec2 a00 = uvec2(p4.x | p5.x | p7.x | p8.x, p4.y & p5.y & p7.y & p8.y), a10 = uvec2(p3.x | p4.x | p6.x | p7.x, p3.y & p4.y & p6.y & p7.y),
          a01 = uvec2(p1.x | p2.x | p4.x | p5.x, p1.y & p2.y & p4.y & p5.y), a11 = uvec2(p0.x | p1.x | p3.x | p4.x, p0.y & p1.y & p3.y & p4.y);
    uvec2 b00 = uvec2(p13.x | p14.x | p16.x | p17.x, p13.y & p14.y & p16.y & p17.y),
          b10 = uvec2(p12.x | p13.x | p15.x | p16.x, p12.y & p13.y & p15.y & p16.y),
          b01 = uvec2(p10.x | p11.x | p13.x | p14.x, p10.y & p11.y & p13.y & p14.y),
          b11 = uvec2(p9.x | p10.x | p12.x | p13.x, p9.y & p10.y & p12.y & p13.y);
    uvec2 c00 = uvec2(p22.x | p23.x | p25.x | p26.x, p22.y & p23.y & p25.y & p26.y),
          c10 = uvec2(p21.x | p22.x | p24.x | p25.x, p21.y & p22.y & p24.y & p25.y),
          c01 = uvec2(p19.x | p20.x | p22.x | p23.x, p19.y & p20.y & p22.y & p23.y),
          c11 = uvec2(p18.x | p19.x | p21.x | p22.x, p18.y & p19.y & p21.y & p22.y);
    // oz = 0: layers dz = 0, +1; oz = 1: dz = -1, 0.
    w[0] = uvec2(b00.x | c00.x, b00.y & c00.y);
    w[1] = uvec2(b10.x | c10.x, b10.y & c10.y);
    w[2] = uvec2(b01.x | c01.x, b01.y & c01.y);
    w[3] = uvec2(b11.x | c11.x, b11.y & c11.y);
    w[4] = uvec2(a00.x | b00.x, a00.y & b00.y);
    w[5] = uvec2(a10.x | b10.x, a10.y & b10.y);
    w[6] = uvec2(a01.x | b01.x, a01.y & b01.y);
    w[7] = uvec2(a11.x | b11.x, a11.y & b11.y);
}

// Decides word `word` of dirty block `block` and marks the cubes around its changed corners; `flips`: fusion's, taken.
void decideWord(uint block, uint word, uint flips, inout uint evaluated) {
    // The corners around which cube o = (ox, oy, oz) is marked (cube corner - o): without refinement, fusion's
    // flips (sign or observed state) for every o.
    uint k[8] = uint[8](flips, flips, flips, flips, flips, flips, flips, flips);
    if (volumeRefines()) {
        uvec4 own = meshSignGroups[block * MASK_WORDS + word];   // its meshing signs and masks
        bool faces;
        uvec4 left, right, other, beyond, lower, upper;
        uint wordEvaluated;
        uint signs = swDecideWord(block, word, own, wordEvaluated, faces, left, right, other, beyond, lower, upper);
        evaluated += wordEvaluated;
        uint signChanged = signs ^ own[MESH_SIGN_MESHING];
        if (signChanged != 0u) meshSigns[block * MESH_SIGN_WORDS + MESH_SIGN_GROUP * word + MESH_SIGN_MESHING] = signs;   // this invocation's word only
        // Which of the cubes around the changed corners may change type (cubeWindow): around a corner whose observed
        // state alone flipped, those with a corner that may be inside for meshing. And where no observation can be
        // taken away this frame (fusion only adds weight: not a de-integration, no recycling, whose starving and
        // retiring lower weights after fusion), only those whose corners are all observed now: a cube with a corner
        // unobserved now had one before, and type 0 then and now. (With recycling, requiring that made emptied
        // blocks wait a frame to be freed in GpuTest.GrowthWithABoundedMapKeepsTheMapOfAmpleCapacities.)
        uint observedOnly = flips & ~signChanged;
        uint need = flips | signChanged;
        [[unroll]] for (uint o = 0u; o < 8u; ++o) k[o] = 0u;
        if (need != 0u) {
            uvec2 w[8];
            cubeWindow(block, word, own, need, faces, left, right, other, beyond, lower, upper, w);
            bool onlyGains = framePose.deintegrate == 0u && params.keepRadius <= 0.0 && params.starveAfterFrames == 0u;
            [[unroll]] for (uint o = 0u; o < 8u; ++o)
                k[o] = (signChanged | (observedOnly & w[o].x)) & (onlyGains ? w[o].y : ~0u);
        }
    }
    uint z = word / 2u, rh = word % 2u;
    // The cubes corner - o, o in {0,1}^3: one row along y lower (oy), one column along x lower (ox: corners at
    // x = 0 reach x = 7 of the block at -x), one layer lower (oz: layer 0 reaches layer 7 at -z).
    [[unroll]] for (uint oz = 0u; oz < 2u; ++oz) {
        int bz = oz == 1u && z == 0u ? -1 : 0;
        uint layer = (z + BLOCK_SIDE - oz) % BLOCK_SIDE;
        [[unroll]] for (uint ox = 0u; ox < 2u; ++ox) {
            uint c0 = k[ox + 4u * oz], c1 = k[ox + 2u + 4u * oz];   // oy = 0, 1
            uint same0 = ox == 1u ? (c0 >> 1) & 0x7F7F7F7Fu : c0, edge0 = ox == 1u ? (c0 & 0x01010101u) << 7 : 0u;
            uint same1 = ox == 1u ? (c1 >> 1) & 0x7F7F7F7Fu : c1, edge1 = ox == 1u ? (c1 & 0x01010101u) << 7 : 0u;
            // oy = 1: rows 1..3 of the word move down in it; its row 0 becomes row 3 of the other word (rh = 1)
            // or row 7 of the block at -y (rh = 0).
            markCubes(block, ivec3(0, 0, bz), layer, rh, same0 | (same1 >> 8));
            markCubes(block, ivec3(-1, 0, bz), layer, rh, edge0 | (edge1 >> 8));
            int by = rh == 0u ? -1 : 0;
            markCubes(block, ivec3(0, by, bz), layer, 1u - rh, (same1 & 0xFFu) << 24);
            markCubes(block, ivec3(-1, by, bz), layer, 1u - rh, (edge1 & 0xFFu) << 24);
        }
    }
}

void main() {
    // Which of this invocation's words have work: fusion flipped a corner, or (with refinement) a corner is near, or
    // a meshing sign differs from the raw one (a corner that was near and flipped, and is not now, takes its raw
    // sign back). Any other word's signs stay raw and it marks nothing, so it is not decided.
    if (gl_LocalInvocationIndex == 0u) activeCount = 0u;
    barrier();
    uint first = gl_GlobalInvocationID.x * DECIDE_WORDS_PER_INVOCATION;
    uint words = counters.dirtyCount * MASK_WORDS;
    uint withWork = 0u, flipsOf[DECIDE_WORDS_PER_INVOCATION];
    [[unroll]] for (uint w = 0u; w < DECIDE_WORDS_PER_INVOCATION; ++w) {
        flipsOf[w] = 0u;
        if (first + w < words) {
            uint at = dirtyList[(first + w) / MASK_WORDS] * MASK_WORDS + (first + w) % MASK_WORDS;
            uint flips = cornerFlips[at];
            if (flips != 0u) cornerFlips[at] = 0u;   // taken
            flipsOf[w] = flips;
            bool work = flips != 0u;
            if (volumeRefines()) {
                uvec4 group = meshSignGroups[at];
                work = work || group[MESH_SIGN_NEAR] != 0u || group[MESH_SIGN_MESHING] != group[MESH_SIGN_RAW];
            }
            if (work) withWork |= 1u << w;
        }
    }
    // List them (one shared atomic per subgroup).
    uint count = bitCount(withWork);
    uint rank = subgroupExclusiveAdd(count), total = subgroupAdd(count), base = 0u;
    if (subgroupElect()) base = atomicAdd(activeCount, total);
    rank += subgroupBroadcastFirst(base);
    [[unroll]] for (uint w = 0u; w < DECIDE_WORDS_PER_INVOCATION; ++w) {
        if ((withWork & (1u << w)) != 0u) {
            activeWords[rank] = first + w;
            activeFlips[rank] = flipsOf[w];
            ++rank;
        }
    }
    barrier();
    uint listed = activeCount, evaluated = 0u;
    for (uint n = gl_LocalInvocationIndex; n < listed; n += gl_WorkGroupSize.x) {   // at most DECIDE_WORDS_PER_INVOCATION times
        uint index = activeWords[n];
        decideWord(dirtyList[index / MASK_WORDS], index % MASK_WORDS, activeFlips[n], evaluated);
    }
    ADD_COUNTER(signCornerCount, evaluated);
}
