#include "core/refinement.h"

#include <bit>
#include <cstddef>

#include "shared_layout.h"
#include <algorithm>
#include <cmath>

namespace vkmesh {

bool isRegularType(int t) {
    for (uint8_t r : kRegularTypes)
        if (t == int(r)) return true;
    return false;
}

int refineType(int prev, int t, const float d[8], float epsilon) {
    if (t == 0 || t == 255 || isRegularType(t)) return t;
    if (std::popcount(unsigned(prev ^ t) & 0xFFu) > 3) return t;
    int best = t;
    float bestSum = 0.0f;
    bool found = false;
    for (uint8_t r : kRegularTypes) {
        const unsigned flipped = unsigned(r ^ t) & 0xFFu;
        if (std::popcount(flipped) > 3) continue;
        bool ok = true;
        float sum = 0.0f;
        for (int i = 0; i < 8; ++i) {
            if (!((flipped >> i) & 1u)) continue;
            const float a = std::fabs(d[i]);
            if (!(a < epsilon)) {
                ok = false;
                break;
            }
            sum += a;
        }
        if (!ok) continue;
        if (!found || sum < bestSum) {  // strict: a tie keeps the earlier regular type
            best = r;
            bestSum = sum;
            found = true;
        }
    }
    return best;
}

}  // namespace vkmesh

namespace vkmesh {

int regularDistance(int t) {
    int best = std::min(std::popcount(unsigned(t) & 0xFFu), std::popcount(~unsigned(t) & 0xFFu));
    for (uint8_t r : kRegularTypes) best = std::min(best, std::popcount(unsigned(r ^ t) & 0xFFu));
    return best;
}

bool refinedCornerInside(const float d[kCornerWindowSize], const bool observed[kCornerWindowSize], float epsilon) {
    const int self = cornerWindowIndex(0, 0, 0);
    const bool inside = d[self] < 0.0f;
    if (!(std::fabs(d[self]) < epsilon)) return inside;
    // Decided only with the 8 cubes around the corner observed (their corners are exactly the window): at the
    // rim of the observed surface a flip would move the rim.
    for (int w = 0; w < kCornerWindowSize; ++w)
        if (!observed[w]) return inside;
    // Cube o has its corner 0 at the corner minus o, so the corner is its corner o.
    int keep = 0, flip = 0;
    for (int o = 0; o < 8; ++o) {
        int t = 0;
        for (int c = 0; c < 8; ++c) {
            const int w = cornerWindowIndex((c & 1) - (o & 1), ((c >> 1) & 1) - ((o >> 1) & 1), ((c >> 2) & 1) - ((o >> 2) & 1));
            if (d[w] < 0.0f) t |= 1 << c;
        }
        keep += regularDistance(t);
        flip += regularDistance(t ^ (1 << o));
    }
    // Flipped, the corner carries a vertex next to it (1/8 of the edge away, edgeCrossing) on each edge to a
    // 6-neighbour of its own raw sign that keeps its sign. On a noisy plane one such neighbour lies across the
    // plane and one in it (a two-corner bump); more would crowd vertices around the corner (sliver fans, and the
    // surface pulled by up to epsilon), so the corner keeps its raw sign then.
    int sameSign = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = -1; side <= 1; side += 2) {
            const int w = cornerWindowIndex(axis == 0 ? side : 0, axis == 1 ? side : 0, axis == 2 ? side : 0);
            sameSign += (d[w] < 0.0f) == inside;
        }
    return flip < keep && sameSign <= 2 ? !inside : inside;  // strictly: a tie keeps the raw sign
}

int refinedCubeType(const float d[kWindowSize], const bool observed[kWindowSize], float epsilon) {
    for (int c = 0; c < 8; ++c)
        if (!observed[windowIndex(c & 1, (c >> 1) & 1, (c >> 2) & 1)]) return 0;
    int type = 0;
    for (int c = 0; c < 8; ++c) {
        float window[kCornerWindowSize];
        bool seen[kCornerWindowSize];
        for (int w = 0; w < kCornerWindowSize; ++w) {
            const int x = (c & 1) + w % 3 - 1, y = ((c >> 1) & 1) + (w / 3) % 3 - 1, z = ((c >> 2) & 1) + w / 9 - 1;
            window[w] = d[windowIndex(x, y, z)];
            seen[w] = observed[windowIndex(x, y, z)];
        }
        if (refinedCornerInside(window, seen, epsilon)) type |= 1 << c;
    }
    return type;
}

}  // namespace vkmesh

// ---- decide_mesh_signs' word decision on the host: the shared code of shaders_comp/retype/sign_window.h ------------
namespace vkmesh::gpu {
struct SwQuad;   // sign_window.h
namespace {
// The block neighbourhood being decided; "block indices" are indices into it (the centre is 13).
thread_local const std::array<const TsdfMasks*, 27>* tlSignBlocks = nullptr;

SwQuad hostSignWords(uint32_t b, uint32_t layer, uint32_t rowHalf);   // below

uint32_t hostSignNeighbor(int ox, int oy, int oz) {
    const int i = cornerWindowIndex(ox, oy, oz);
    return (*tlSignBlocks)[std::size_t(i)] ? uint32_t(i) : NO_BLOCK;
}
}  // namespace
}  // namespace vkmesh::gpu

#define SIGN_WINDOW_WORDS(b, layer, rowHalf) hostSignWords(b, layer, rowHalf)
#define SIGN_WINDOW_NEIGHBOR(b, ox, oy, oz) hostSignNeighbor(ox, oy, oz)
#include "retype/sign_window.h"
#undef SIGN_WINDOW_WORDS
#undef SIGN_WINDOW_NEIGHBOR

namespace vkmesh::gpu {
namespace {
// A mask word's group as the GPU reads it (shared_layout.h, MESH_SIGN_GROUP): the meshing signs (not read by the
// decision: 0), raw, near, observed.
SwQuad hostSignWords(uint32_t b, uint32_t layer, uint32_t rowHalf) {
    if (b == NO_BLOCK) return {0u, 0u, 0u, 0u};
    const TsdfMasks& t = *(*tlSignBlocks)[b];
    const uint32_t w = 2 * layer + rowHalf;
    return {0u, t.raw[w], t.near[w], t.observed[w]};
}
}  // namespace
}  // namespace vkmesh::gpu

namespace vkmesh {

TsdfMasks tsdfMasks(const float sdf[512], const float weight[512], float minMeshWeight, float epsilon) {
    TsdfMasks m;
    for (uint32_t local = 0; local < 512; ++local) {
        const uint32_t bit = 1u << (local % 32), w = local / 32;
        const bool observed = weight[local] >= minMeshWeight;
        if (sdf[local] < 0.0f) m.raw[w] |= bit;
        if (observed && std::fabs(sdf[local]) < epsilon) m.near[w] |= bit;
        if (observed) m.observed[w] |= bit;
    }
    return m;
}

uint32_t refinedSignWord(const std::array<const TsdfMasks*, 27>& blocks, uint32_t word, uint32_t* evaluated) {
    gpu::tlSignBlocks = &blocks;
    uint32_t n = 0;
    const uint32_t centre = uint32_t(cornerWindowIndex(0, 0, 0));
    const uint32_t signs = gpu::swDecideWord(centre, word, gpu::hostSignWords(centre, word / 2, word % 2), n);
    gpu::tlSignBlocks = nullptr;
    if (evaluated) *evaluated = n;
    return signs;
}

}  // namespace vkmesh
