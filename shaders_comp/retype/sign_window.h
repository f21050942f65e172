// Refinement by bit operations (docs/REFINEMENT.md, "Decided once per corner"): the meshing signs of one word
// of 32 corners (4 rows along x of one z layer: corner x + 8 (y + 8 z), word k = (z, rows 4 (k % 2) .. +3)),
// decided from per-block bit masks of the TSDF that fusion keeps (shared_layout.h, MESH_SIGN_RAW/NEAR/OBSERVED)
// instead of the corners' sdf and weight. The same pure function as refinedCornerInside (src/core/refinement.cpp):
//   - the 27 words "mask at corner + (dx, dy, dz)" for the word's 32 corners are shifts and ors of the mask words
//     of the block and of its neighbours (a row end takes the x-neighbour's column, the word's first or last row
//     the adjacent word's or the y-neighbour's row, a layer at 0 or 7 the z-neighbour's);
//   - a corner may flip only when it is near (observed, |d| < epsilon), at most 2 of its 6 edge neighbours share
//     its raw sign (bit-sliced, all 32 at once, from 7 mask words) and its 27 corners are observed;
//   - the window of the corners left is read once for the raw and the observed masks: a mask word's four words are
//     one group (MESH_SIGN_GROUP, shared_layout.h), read as one uvec4, and on llvmpipe a uvec4 load per lane costs
//     what a uint load does. The observed window, which took 27 loads of its own after the decision, is now free
//     (decide_mesh_signs 1.04 -> 0.84 ms on the synthetic room), so it goes first (the AND of 27 shifted words);
//   - each remaining corner is decided from its 27 window bits (pure ALU: cube types by shifts, regular
//     distances by xor and bitCount).
// Shared by the GPU (decide_mesh_signs.comp) and its CPU twin (refinedSignWord, src/core/refinement.cpp, unit-tested
// against refinedCornerInside), so the two cannot drift apart. The includer defines how words are read:
//   SIGN_WINDOW_WORDS(b, layer, rowHalf)  the group of word 2 layer + rowHalf of block b (SwQuad: the meshing signs,
//                                         raw, near, observed; MESH_SIGN_*), all 0 if b == NO_BLOCK
//   SIGN_WINDOW_NEIGHBOR(b, ox, oy, oz)  the block at offset (ox, oy, oz) in {-1, 0, 1}^3 from b (b itself at 0)
#ifndef VKMESH_SIGN_WINDOW_H
#define VKMESH_SIGN_WINDOW_H

#ifdef __cplusplus
#include <bit>
#include <cstdint>

#include "shared_layout.h"
namespace vkmesh::gpu {
inline int bitCount(uint x) { return std::popcount(x); }
inline int findLSB(uint x) { return x == 0u ? -1 : std::countr_zero(x); }
#define SW_FN inline
#define SW_OUT(T) T&
#define SW_UNROLL
// GLSL's uvec4 and uvec2, as far as the windows use them: a group of a mask word's words, and a (raw, observed) pair
// that the shifts and masks below act on component by component.
struct SwQuad {
    uint x, y, z, w;
};
struct SwPair {
    uint x, y;
};
inline SwPair operator&(SwPair a, uint b) { return {a.x & b, a.y & b}; }
inline SwPair operator|(SwPair a, SwPair b) { return {a.x | b.x, a.y | b.y}; }
inline SwPair operator<<(SwPair a, uint n) { return {a.x << n, a.y << n}; }
inline SwPair operator>>(SwPair a, uint n) { return {a.x >> n, a.y >> n}; }
inline SwPair swRawObserved(SwQuad q) { return {q.y, q.w}; }
// (raw sign or near, observed): a corner inside for meshing is one of these (only a near corner flips).
inline SwPair swMayBeInsideObserved(SwQuad q) { return {q.y | q.z, q.w}; }
#define SW_PAIR_ZERO SwPair{0u, 0u}
#else
#define SW_FN
#define SW_OUT(T) out T
#define SW_UNROLL [[unroll]]   // llvmpipe does not unroll short fixed loops itself (frame.glsl)
#define SwQuad uvec4
#define SwPair uvec2
SwPair swRawObserved(SwQuad q) { return q.yw; }
SwPair swMayBeInsideObserved(SwQuad q) { return uvec2(q.y | q.z, q.w); }
#define SW_PAIR_ZERO uvec2(0u)
#endif

// A word of 4 rows with every corner replaced by its neighbour at dx along x: `left` and `right` are the same
// rows of the blocks at -x and +x (their x = 7 and x = 0 columns enter at the row ends).
SW_FN uint swShiftX(uint here, uint left, uint right, int dx) {
    if (dx > 0) return ((here >> 1) & 0x7F7F7F7Fu) | ((right & 0x01010101u) << 7);
    if (dx < 0) return ((here << 1) & 0xFEFEFEFEu) | ((left >> 7) & 0x01010101u);
    return here;
}
SW_FN SwPair swShiftX(SwPair here, SwPair left, SwPair right, int dx) {   // the same, for a (raw, observed) pair
    if (dx > 0) return ((here >> 1u) & 0x7F7F7F7Fu) | ((right & 0x01010101u) << 7u);
    if (dx < 0) return ((here << 1u) & 0xFEFEFEFEu) | ((left >> 7u) & 0x01010101u);
    return here;
}

SW_FN SwPair swPick(SwQuad q, bool mayBeInside) { return mayBeInside ? swMayBeInsideObserved(q) : swRawObserved(q); }

// Rows 4 rh .. 4 rh + 3 of layer `layer` of the raw and observed masks of block b, shifted by dy = -1 (down), 0 (mid), +1 (up): the
// row below / above comes from the block's other word or, past the block's side, from block `by` (the
// y-neighbour of b on that side: -y when rh = 0, +y when rh = 1). Only the bits of `need` are read by the caller:
// the row below is loaded only for a bit in row 0, the row above only for one in row 3, nothing without a bit (on
// llvmpipe a load that a lane skips is a load saved, and the windows' loads are most of the decision's cost).
// `have` bit 0, 1, 2: the rows, the other word and the word beyond were read already (rowsIn, otherIn, beyondIn:
// the words rule 3 read) and are not read again. `mayBeInside`: the pairs are (raw sign or near, observed) instead
// of (raw sign, observed) (decide_mesh_signs' cube window).
SW_FN void swColumnRows(uint b, uint by, uint layer, uint rh, uint need, uint have, SwPair rowsIn, SwPair otherIn, SwPair beyondIn,
                        bool mayBeInside, SW_OUT(SwPair) down, SW_OUT(SwPair) mid, SW_OUT(SwPair) up) {
    bool needBelow = (need & 0xFFu) != 0u, needAbove = (need & 0xFF000000u) != 0u;
    SwPair rows = (have & 1u) != 0u ? rowsIn : (need != 0u ? swPick(SIGN_WINDOW_WORDS(b, layer, rh), mayBeInside) : SW_PAIR_ZERO);
    SwPair other = (have & 2u) != 0u ? otherIn
                   : ((rh == 0u ? needAbove : needBelow) ? swPick(SIGN_WINDOW_WORDS(b, layer, 1u - rh), mayBeInside) : SW_PAIR_ZERO);
    SwPair beyond = (have & 4u) != 0u ? beyondIn
                    : ((rh == 0u ? needBelow : needAbove) ? swPick(SIGN_WINDOW_WORDS(by, layer, 1u - rh), mayBeInside) : SW_PAIR_ZERO);
    SwPair below = rh == 0u ? beyond >> 24u : other >> 24u;
    SwPair above = rh == 0u ? other & 0xFFu : beyond & 0xFFu;
    down = (rows << 8u) | below;
    mid = rows;
    up = (rows >> 8u) | (above << 24u);
}

// The 9 shifted (raw, observed) pairs of layer dz of the window: w[(dx + 1) + 3 (dy + 1)] = masks at corner + (dx, dy, dz)
// for the 32 corners of word (z, rh) of `block`, exact at the bits of `need` (elsewhere they may be 0): the columns
// of the blocks at -x / +x are read only for a bit at x = 0 / x = 7, a y-neighbour only for a bit in the row next
// to it (the window of a word's few candidates: retype 1.87 -> 1.76 ms on the synthetic room). `have` bits 0-2: the
// middle column's rows, other word and word beyond were read already (swColumnRows); bits 3, 4: the rows of the
// -x / +x column (rowsL, rowsR).
SW_FN void swLayer(uint block, uint z, uint rh, int dz, uint need, uint have, SwPair rowsMid, SwPair otherMid, SwPair beyondMid,
                   SwPair rowsL, SwPair rowsR, bool mayBeInside, SW_OUT(SwPair) w0, SW_OUT(SwPair) w1, SW_OUT(SwPair) w2, SW_OUT(SwPair) w3,
                   SW_OUT(SwPair) w4, SW_OUT(SwPair) w5, SW_OUT(SwPair) w6, SW_OUT(SwPair) w7, SW_OUT(SwPair) w8) {
    int zz = int(z) + dz;
    int oz = zz < 0 ? -1 : (zz > 7 ? 1 : 0);
    uint layer = uint(zz - 8 * oz);
    int oy = rh == 0u ? -1 : 1;
    uint needL = need & 0x01010101u, needR = need & 0x80808080u;
    uint edgeRow = rh == 0u ? 0x000000FFu : 0xFF000000u;   // the row whose dy step leaves the block
    uint otherRow = rh == 0u ? 0xFF000000u : 0x000000FFu;  // the row whose dy step reaches the block's other word
    // A column's block is looked up only for a word still to be read.
    uint lookL = (have & 8u) != 0u ? needL & otherRow : needL, lookR = (have & 16u) != 0u ? needR & otherRow : needR;
    uint lookMid = (have & 1u) != 0u ? ((have & 2u) != 0u ? 0u : need & otherRow) : need;
    SwPair dL, mL, uL, d0, m0, u0, dR, mR, uR;
    swColumnRows(lookL != 0u ? SIGN_WINDOW_NEIGHBOR(block, -1, 0, oz) : NO_BLOCK,
                 (needL & edgeRow) != 0u ? SIGN_WINDOW_NEIGHBOR(block, -1, oy, oz) : NO_BLOCK, layer, rh, needL, (have >> 3) & 1u,
                 rowsL, SW_PAIR_ZERO, SW_PAIR_ZERO, mayBeInside, dL, mL, uL);
    swColumnRows(oz == 0 ? block : (lookMid != 0u ? SIGN_WINDOW_NEIGHBOR(block, 0, 0, oz) : NO_BLOCK),
                 (need & edgeRow) != 0u && (have & 4u) == 0u ? SIGN_WINDOW_NEIGHBOR(block, 0, oy, oz) : NO_BLOCK, layer, rh, need,
                 have & 7u, rowsMid, otherMid, beyondMid, mayBeInside, d0, m0, u0);
    swColumnRows(lookR != 0u ? SIGN_WINDOW_NEIGHBOR(block, 1, 0, oz) : NO_BLOCK,
                 (needR & edgeRow) != 0u ? SIGN_WINDOW_NEIGHBOR(block, 1, oy, oz) : NO_BLOCK, layer, rh, needR, (have >> 4) & 1u,
                 rowsR, SW_PAIR_ZERO, SW_PAIR_ZERO, mayBeInside, dR, mR, uR);
    w0 = swShiftX(d0, dL, dR, -1);
    w1 = d0;
    w2 = swShiftX(d0, dL, dR, 1);
    w3 = swShiftX(m0, mL, mR, -1);
    w4 = m0;
    w5 = swShiftX(m0, mL, mR, 1);
    w6 = swShiftX(u0, uL, uR, -1);
    w7 = u0;
    w8 = swShiftX(u0, uL, uR, 1);
}

// Bit-sliced over 32 corners: set where at most 2 of the 6 bits e1..e6 are set.
SW_FN uint swAtMostTwo(uint e1, uint e2, uint e3, uint e4, uint e5, uint e6) {
    uint sa = e1 ^ e2 ^ e3, ca = (e1 & e2) | (e3 & (e1 ^ e2));
    uint sb = e4 ^ e5 ^ e6, cb = (e4 & e5) | (e6 & (e4 ^ e5));
    uint s0 = sa ^ sb, c0 = sa & sb;   // count = s0 + 2 (ca + cb + c0)
    uint s1 = ca ^ cb ^ c0, s2 = (ca & cb) | (c0 & (ca ^ cb));
    return ~(s2 | (s1 & s0));
}

// regularDistance (src/core/refinement.cpp): Hamming distance from t to the nearest of 0, 255 and the six half-cube
// types; those come in complementary pairs, so the distance to a pair {r, ~r} is min(n, 8 - n), n = bitCount(t ^ r).
SW_FN int swRegularDistance(uint t) {
    int best = 8;
    SW_UNROLL for (uint k = 0u; k < 4u; ++k) {
        uint r = k == 0u ? 0u : (k == 1u ? 0x0Fu : (k == 2u ? 0x33u : 0x55u));
        int n = bitCount(t ^ r);
        n = n < 8 - n ? n : 8 - n;
        best = n < best ? n : best;
    }
    return best;
}

// The MC type of cube o around the window's centre (its corner 0 at the centre minus o), from the window's raw
// signs `win` (bit (x + 1) + 3 (y + 1) + 9 (z + 1)): its corners c are window bits w0 + {0, 1, 3, 4, 9, 10, 12, 13}.
SW_FN uint swCubeType(uint win, uint o) {
    uint w0 = (1u - (o & 1u)) + 3u * (1u - ((o >> 1) & 1u)) + 9u * (1u - ((o >> 2) & 1u));
    uint x = win >> w0;
    return (x & 3u) | ((x >> 1) & 0xCu) | ((x >> 5) & 0x30u) | ((x >> 6) & 0xC0u);
}

// Whether a near corner with an all-observed window flips (refinedCornerInside's rules 2 and 3).
SW_FN bool swFlips(uint win) {
    int keep = 0, flip = 0;
    SW_UNROLL for (uint o = 0u; o < 8u; ++o) {
        uint t = swCubeType(win, o);
        keep += swRegularDistance(t);
        flip += swRegularDistance(t ^ (1u << o));
    }
    const uint edgeNeighbours = (1u << 4) | (1u << 10) | (1u << 12) | (1u << 14) | (1u << 16) | (1u << 22);
    uint sameSign = ((win >> 13) & 1u) != 0u ? win & edgeNeighbours : ~win & edgeNeighbours;
    return flip < keep && bitCount(sameSign) <= 2;
}

// The meshing signs of word `word` of `block` (bit i: corner 32 word + i inside for meshing), given the word's group
// `own` (SIGN_WINDOW_WORDS). `evaluated`: the corners whose window had to be decided bit by bit (the others kept
// their raw sign by the masks alone). `faces`: whether the groups of the word's 6 edge neighbours (rule 3's words:
// the blocks at -x and +x, the other word of the layer, the y-neighbour's, the layers below and above) were read,
// and then those groups, for a caller that needs them too (decide_mesh_signs' cube window).
SW_FN uint swDecideWord(uint block, uint word, SwQuad own, SW_OUT(uint) evaluated, SW_OUT(bool) faces, SW_OUT(SwQuad) leftGroup,
                        SW_OUT(SwQuad) rightGroup, SW_OUT(SwQuad) otherGroup, SW_OUT(SwQuad) beyondGroup, SW_OUT(SwQuad) lowerGroup,
                        SW_OUT(SwQuad) upperGroup) {
    uint z = word / 2u, rh = word % 2u;
    uint raw = own.y;
    uint cand = own.z;   // near
    evaluated = 0u;
    faces = cand != 0u;
    if (cand == 0u) return raw;
    // Rule 3 first, from the 6 edge neighbours' words only (7 mask words): at most 2 of them share the sign. On a
    // surface a near corner has 4 or 5 (its layer's neighbours and one across), so this removes most of them.
    // Its words are the window's too (kept with their observed words, not read again below).
    int oy = rh == 0u ? -1 : 1;
    leftGroup = SIGN_WINDOW_WORDS(SIGN_WINDOW_NEIGHBOR(block, -1, 0, 0), z, rh);
    rightGroup = SIGN_WINDOW_WORDS(SIGN_WINDOW_NEIGHBOR(block, 1, 0, 0), z, rh);
    otherGroup = SIGN_WINDOW_WORDS(block, z, 1u - rh);
    beyondGroup = SIGN_WINDOW_WORDS(SIGN_WINDOW_NEIGHBOR(block, 0, oy, 0), z, 1u - rh);
    lowerGroup = z == 0u ? SIGN_WINDOW_WORDS(SIGN_WINDOW_NEIGHBOR(block, 0, 0, -1), 7u, rh) : SIGN_WINDOW_WORDS(block, z - 1u, rh);
    upperGroup = z == 7u ? SIGN_WINDOW_WORDS(SIGN_WINDOW_NEIGHBOR(block, 0, 0, 1), 0u, rh) : SIGN_WINDOW_WORDS(block, z + 1u, rh);
    SwPair left = swRawObserved(leftGroup), right = swRawObserved(rightGroup), other = swRawObserved(otherGroup);
    SwPair beyond = swRawObserved(beyondGroup), lower = swRawObserved(lowerGroup), upper = swRawObserved(upperGroup);
    {
        uint below = rh == 0u ? beyond.x >> 24 : other.x >> 24;
        uint above = rh == 0u ? other.x & 0xFFu : beyond.x & 0xFFu;
        cand &= swAtMostTwo(~(swShiftX(raw, left.x, right.x, -1) ^ raw), ~(swShiftX(raw, left.x, right.x, 1) ^ raw),
                            ~(((raw << 8) | below) ^ raw), ~(((raw >> 8) | (above << 24)) ^ raw), ~(lower.x ^ raw), ~(upper.x ^ raw));
    }
    if (cand == 0u) return raw;
    // The window of the raw and the observed masks at once (pN.x raw, pN.y observed, at corner + offset N).
    SwPair p0, p1, p2, p3, p4, p5, p6, p7, p8, p9, p10, p11, p12, p13, p14, p15, p16, p17, p18, p19, p20, p21, p22, p23,
        p24, p25, p26;
    swLayer(block, z, rh, -1, cand, 1u, lower, SW_PAIR_ZERO, SW_PAIR_ZERO, SW_PAIR_ZERO, SW_PAIR_ZERO, false, p0, p1, p2, p3, p4, p5, p6, p7, p8);
    swLayer(block, z, rh, 0, cand, 31u, swRawObserved(own), other, beyond, left, right, false, p9, p10, p11, p12, p13, p14, p15, p16, p17);
    swLayer(block, z, rh, 1, cand, 1u, upper, SW_PAIR_ZERO, SW_PAIR_ZERO, SW_PAIR_ZERO, SW_PAIR_ZERO, false, p18, p19, p20, p21, p22, p23, p24,
            p25, p26);
    // The observed rule first, as it costs no load of its own: a flip needs the corner's 27 corners observed (the AND
    // of the 27 shifted words of the observed mask, exact at the candidates).
    cand &= p0.y & p1.y & p2.y & p3.y & p4.y & p5.y & p6.y & p7.y & p8.y & p9.y & p10.y & p11.y & p12.y & p13.y &
            p14.y & p15.y & p16.y & p17.y & p18.y & p19.y & p20.y & p21.y & p22.y & p23.y & p24.y & p25.y &
            p26.y;
    uint flips = 0u;
    for (uint k = 0u; k < 32u && cand != 0u; ++k) {   // over the candidates (at most 32)
        uint b = uint(findLSB(cand));
        cand &= cand - 1u;
        uint win = ((p0.x >> b) & 1u) | (((p1.x >> b) & 1u) << 1u) | (((p2.x >> b) & 1u) << 2u) |
                   (((p3.x >> b) & 1u) << 3u) | (((p4.x >> b) & 1u) << 4u) | (((p5.x >> b) & 1u) << 5u) |
                   (((p6.x >> b) & 1u) << 6u) | (((p7.x >> b) & 1u) << 7u) | (((p8.x >> b) & 1u) << 8u) |
                   (((p9.x >> b) & 1u) << 9u) | (((p10.x >> b) & 1u) << 10u) | (((p11.x >> b) & 1u) << 11u) |
                   (((p12.x >> b) & 1u) << 12u) | (((p13.x >> b) & 1u) << 13u) | (((p14.x >> b) & 1u) << 14u) |
                   (((p15.x >> b) & 1u) << 15u) | (((p16.x >> b) & 1u) << 16u) | (((p17.x >> b) & 1u) << 17u) |
                   (((p18.x >> b) & 1u) << 18u) | (((p19.x >> b) & 1u) << 19u) | (((p20.x >> b) & 1u) << 20u) |
                   (((p21.x >> b) & 1u) << 21u) | (((p22.x >> b) & 1u) << 22u) | (((p23.x >> b) & 1u) << 23u) |
                   (((p24.x >> b) & 1u) << 24u) | (((p25.x >> b) & 1u) << 25u) | (((p26.x >> b) & 1u) << 26u);
        ++evaluated;
        if (swFlips(win)) flips |= 1u << b;
    }
    return raw ^ flips;
}

SW_FN uint swDecideWord(uint block, uint word, SwQuad own, SW_OUT(uint) evaluated) {
    bool faces;
    SwQuad l, r, o, b, lo, up;
    return swDecideWord(block, word, own, evaluated, faces, l, r, o, b, lo, up);
}

#undef SW_FN
#undef SW_OUT
#undef SW_UNROLL
#ifdef __cplusplus
}  // namespace vkmesh::gpu
#endif
#endif
