// refineType (docs/REFINEMENT.md, paper §V.F): the regular-type table and the pure function the CPU reference
// mesher and the GPU (shaders_comp/structure/cube_access.glsl) both apply.
#include "core/refinement.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>
#include <iostream>
#include <set>
#include <vector>

#include "core/marching_cubes.h"

namespace vkmesh {
namespace {

constexpr float kEps = 0.01f;

// Corner values giving type t: inside corners -0.05, outside +0.05 (both far beyond kEps), then `near`
// overrides some corners with small values of the right sign.
struct Corners {
    float d[8];
    explicit Corners(int t) {
        for (int i = 0; i < 8; ++i) d[i] = ((t >> i) & 1) ? -0.05f : 0.05f;
    }
    Corners& set(int corner, float value) {
        d[corner] = value;
        return *this;
    }
};

TEST(Refinement, RegularTypesAreTheSixHalfCubesInTableOrder) {
    // Expected order: inside half z = 0, z = 1, y = 0, y = 1, x = 0, x = 1.
    const int axisOf[6] = {2, 2, 1, 1, 0, 0}, valueOf[6] = {0, 1, 0, 1, 0, 1};
    std::set<int> seen;
    for (int k = 0; k < 6; ++k) {
        const int r = kRegularTypes[k];
        EXPECT_EQ(std::popcount(unsigned(r)), 4) << "type " << r;
        int expected = 0;
        for (int c = 0; c < 8; ++c)
            if (cornerCoord(c, axisOf[k]) == valueOf[k]) expected |= 1 << c;
        EXPECT_EQ(r, expected) << "entry " << k << " is not the half cube axis " << axisOf[k] << " = " << valueOf[k];
        // A half cube: its 4 corners share one coordinate.
        bool half = false;
        for (int axis = 0; axis < 3; ++axis)
            for (int v = 0; v < 2; ++v) {
                bool all = true;
                for (int c = 0; c < 8; ++c)
                    if (((r >> c) & 1) && cornerCoord(c, axis) != v) all = false;
                half = half || all;
            }
        EXPECT_TRUE(half) << "type " << r;
        seen.insert(r);
    }
    EXPECT_EQ(seen.size(), 6u);
    // A half cube has exactly 2 triangles (a quad) in vkmesh's MC table.
    for (uint8_t r : kRegularTypes) EXPECT_EQ(marchingCubesTables().triangleCount[r], 2) << int(r);
}

TEST(Refinement, TableIsClosedUnderComplement) {
    for (uint8_t r : kRegularTypes) EXPECT_TRUE(isRegularType(~r & 0xFF)) << int(r);
    int regular = 0;
    for (int t = 0; t < 256; ++t) regular += isRegularType(t) ? 1 : 0;
    EXPECT_EQ(regular, 6);
    EXPECT_FALSE(isRegularType(0));
    EXPECT_FALSE(isRegularType(255));
}

TEST(Refinement, TrivialAndRegularTypesAreKept) {
    for (int t : {0, 255, 0x0F, 0xF0, 0x33, 0xCC, 0x55, 0xAA}) {
        float d[8];
        for (float& v : d) v = (t == 0) ? 0.001f : -0.001f;  // every corner within epsilon
        for (int prev : {0, t, 0x07, 0xFF})
            EXPECT_EQ(refineType(prev, t, d, kEps), t) << "t " << t << " prev " << prev;
    }
}

TEST(Refinement, OneCornerOffSnapsOnlyWithinEpsilon) {
    // 0x07: corners 0, 1, 2 inside; corner 3 (the 4th of the z = 0 face) just outside.
    const int t = 0x07;
    const Corners close = Corners(t).set(3, 0.004f);
    ASSERT_EQ(cubeType(close.d), t);
    EXPECT_EQ(refineType(0x0F, t, close.d, kEps), 0x0F);
    EXPECT_EQ(refineType(t, t, close.d, kEps), 0x0F);
    EXPECT_EQ(refineType(0, t, close.d, kEps), 0x0F);  // popcount(0 ^ 0x07) = 3
    // Just outside epsilon (and exactly at it: |d| < epsilon is strict): stays.
    EXPECT_EQ(refineType(0x0F, t, Corners(t).set(3, 0.02f).d, kEps), t);
    EXPECT_EQ(refineType(0x0F, t, Corners(t).set(3, kEps).d, kEps), t);
    // The other side: 0x1F (0x0F plus corner 4 just inside) snaps back to 0x0F.
    const Corners extra = Corners(0x1F).set(4, -0.003f);
    ASSERT_EQ(cubeType(extra.d), 0x1F);
    EXPECT_EQ(refineType(0x1F, 0x1F, extra.d, kEps), 0x0F);
    // Negative epsilon or zero: nothing is within it.
    EXPECT_EQ(refineType(0x0F, t, close.d, 0.0f), t);
}

TEST(Refinement, FarFromThePreviousTypeStays) {
    const int t = 0x07;
    const Corners close = Corners(t).set(3, 0.004f);
    // popcount(prev ^ t) = 4: stays; = 3: snaps.
    const int prev4 = t ^ 0x1E, prev3 = t ^ 0x0E;
    ASSERT_EQ(std::popcount(unsigned(prev4 ^ t)), 4);
    ASSERT_EQ(std::popcount(unsigned(prev3 ^ t)), 3);
    EXPECT_EQ(refineType(prev4, t, close.d, kEps), t);
    EXPECT_EQ(refineType(prev3, t, close.d, kEps), 0x0F);
    EXPECT_EQ(refineType(0xF0, t, close.d, kEps), t);  // 7 apart
}

TEST(Refinement, SmallestSumWinsTiesGoToTheEarlierType) {
    // t = 0x03 (corners 0, 1 inside) lies 2 flips from 0x0F (corners 2, 3) and 2 from 0x33 (corners 4, 5).
    const int t = 0x03;
    Corners c(t);
    c.set(2, 0.004f).set(3, 0.004f).set(4, 0.004f).set(5, 0.004f);
    ASSERT_EQ(cubeType(c.d), t);
    EXPECT_EQ(refineType(t, t, c.d, kEps), 0x0F) << "equal sums: the earlier regular type";
    c.set(4, 0.003f);
    EXPECT_EQ(refineType(t, t, c.d, kEps), 0x33) << "a smaller sum wins whatever the order";
    c.set(4, 0.004f).set(2, 0.02f);
    EXPECT_EQ(refineType(t, t, c.d, kEps), 0x33) << "0x0F is no candidate (corner 2 beyond epsilon)";
    // 0x0A (corners 1, 3 inside) between 0xAA (flip 5, 7) and 0x0F (flip 0, 2): a tie to 0x0F (earlier) ...
    Corners e(0x0A);
    e.set(0, 0.005f).set(2, 0.005f).set(5, 0.005f).set(7, 0.005f);
    ASSERT_EQ(cubeType(e.d), 0x0A);
    EXPECT_EQ(refineType(0x0A, 0x0A, e.d, kEps), 0x0F);
    // ... and 0xAA when its corners are closer.
    e.set(5, 0.001f);
    EXPECT_EQ(refineType(0x0A, 0x0A, e.d, kEps), 0xAA);
}

// Random corners and every (prev, t): the result is t or a regular type within 3 flips of t whose flipped
// corners are all within epsilon, only when prev is within 3 of t; no candidate has a smaller sum; no earlier
// candidate has the same sum.
TEST(Refinement, PropertiesOnRandomCorners) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> value(-0.03f, 0.03f);
    size_t snapped = 0;
    for (int trial = 0; trial < 400; ++trial) {
        float d[8];
        for (float& v : d) v = value(rng);
        for (int t = 0; t < 256; ++t) {
            for (int prev = 0; prev < 256; prev += 3) {
                const int r = refineType(prev, t, d, kEps);
                ASSERT_LE(std::popcount(unsigned(r ^ t)), 3) << "prev " << prev << " t " << t;
                if (r == t) continue;
                ++snapped;
                ASSERT_TRUE(isRegularType(r));
                ASSERT_FALSE(isRegularType(t) || t == 0 || t == 255);
                ASSERT_LE(std::popcount(unsigned(prev ^ t)), 3);
                auto sumOf = [&](int candidate, bool& ok) {
                    float sum = 0.0f;
                    ok = std::popcount(unsigned(candidate ^ t)) <= 3;
                    for (int i = 0; i < 8; ++i)
                        if (((candidate ^ t) >> i) & 1) {
                            ok = ok && std::fabs(d[i]) < kEps;
                            sum += std::fabs(d[i]);
                        }
                    return sum;
                };
                bool ok = false;
                const float best = sumOf(r, ok);
                ASSERT_TRUE(ok);
                bool before = true;
                for (uint8_t other : kRegularTypes) {
                    if (other == r) {
                        before = false;
                        continue;
                    }
                    bool otherOk = false;
                    const float sum = sumOf(other, otherOk);
                    if (!otherOk) continue;
                    ASSERT_GE(sum, best);
                    if (before) {
                        ASSERT_GT(sum, best) << "a tie must go to the earlier type";
                    }
                }
            }
        }
    }
    EXPECT_GT(snapped, 1000u);
}

}  // namespace
}  // namespace vkmesh

// ---- the per-corner rule the meshers use (refinedCubeType) ------------------------------------------------

namespace vkmesh {
namespace {

TEST(CornerRefinement, RegularDistanceCountsFlipsToTheNearestGoodType) {
    for (int t : {0, 255, 0x0F, 0xF0, 0x33, 0xCC, 0x55, 0xAA}) EXPECT_EQ(regularDistance(t), 0) << t;
    EXPECT_EQ(regularDistance(0x01), 1);  // one corner inside: one flip from empty
    EXPECT_EQ(regularDistance(0x07), 1);  // three of the z = 0 face: one flip from 0x0F
    EXPECT_EQ(regularDistance(0x81), 2);  // two opposite corners
    for (int t = 0; t < 256; ++t) {
        EXPECT_LE(regularDistance(t), 4) << t;
        EXPECT_EQ(regularDistance(t), regularDistance(~t & 0xFF)) << t;  // symmetric under inside/outside
    }
}

// A field over the grid; window of the cube with corner 0 at (x, y, z).
struct Field {
    int n;
    std::vector<float> v;
    float at(int x, int y, int z) const { return v[size_t(x + n * (y + n * z))]; }
    int refined(int x, int y, int z, float eps) const {
        float d[kWindowSize];
        bool observed[kWindowSize];
        for (int w = 0; w < kWindowSize; ++w) {
            d[w] = at(x + w % 4 - 1, y + (w / 4) % 4 - 1, z + w / 16 - 1);
            observed[w] = true;
        }
        return refinedCubeType(d, observed, eps);
    }
    int raw(int x, int y, int z) const {
        int t = 0;
        for (int c = 0; c < 8; ++c)
            if (at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)) < 0.0f) t |= 1 << c;
        return t;
    }
};

// A horizontal plane z = 2.5 (voxels) with one corner of the z = 2 layer nudged just outside: raw, the four
// cubes around it are irregular; refined, the corner flips back and all of them are the half cube 0x0F.
TEST(CornerRefinement, ANoisyCornerOnAPlaneSnapsBack) {
    Field f{7, std::vector<float>(343)};
    for (int z = 0; z < 7; ++z)
        for (int y = 0; y < 7; ++y)
            for (int x = 0; x < 7; ++x) f.v[size_t(x + 7 * (y + 7 * z))] = float(z) - 2.5f;
    f.v[size_t(3 + 7 * (3 + 7 * 2))] = 0.1f;  // corner (3, 3, 2): was -0.5
    EXPECT_EQ(f.raw(2, 2, 2), 0x07);  // the corner is corner 3 of this cube
    EXPECT_EQ(f.raw(2, 2, 1), 0x7F);  // and corner 7 of the one below
    for (int cy = 2; cy <= 3; ++cy)
        for (int cx = 2; cx <= 3; ++cx) {
            EXPECT_EQ(f.refined(cx, cy, 2, 0.5f), 0x0F) << cx << " " << cy;
            EXPECT_EQ(f.refined(cx, cy, 2, 0.05f), f.raw(cx, cy, 2)) << "epsilon below |d|: no flip";
            // The cubes below (z = 1 .. 2) see the same flip: all inside again.
            EXPECT_EQ(f.refined(cx, cy, 1, 0.5f), 0xFF);
        }
}

// On a random field near zero: neighbouring cubes agree on every shared corner (no cracks), a corner whose
// refined sign differs from its raw sign lies within epsilon, and the irregular share goes down.
TEST(CornerRefinement, NeighboursAgreeOnSharedCornersAndOnlyNearCornersFlip) {
    const int n = 14;
    Field f{n, std::vector<float>(size_t(n * n * n))};
    std::mt19937 rng(7);
    std::normal_distribution<float> noise(0.0f, 0.15f);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) f.v[size_t(x + n * (y + n * z))] = 0.1f * float(x) + 0.05f * float(y) + float(z) - 6.3f + noise(rng);
    const float eps = 0.5f;
    size_t surface = 0, irregularRaw = 0, irregularRefined = 0, flippedCorners = 0;
    for (int z = 1; z < n - 3; ++z)
        for (int y = 1; y < n - 3; ++y)
            for (int x = 1; x < n - 3; ++x) {
                const int r = f.refined(x, y, z, eps), t = f.raw(x, y, z);
                for (int c = 0; c < 8; ++c)
                    if (((r ^ t) >> c) & 1) {
                        ++flippedCorners;
                        ASSERT_LT(std::fabs(f.at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1))), eps);
                    }
                if (t != 0 && t != 255) {
                    ++surface;
                    irregularRaw += isRegularType(t) ? 0 : 1;
                }
                if (r != 0 && r != 255) irregularRefined += isRegularType(r) ? 0 : 1;
                for (int axis = 0; axis < 3; ++axis) {
                    if ((axis == 0 ? x : axis == 1 ? y : z) + 1 >= n - 3) continue;
                    const int u = f.refined(x + (axis == 0), y + (axis == 1), z + (axis == 2), eps);
                    for (int c = 0; c < 8; ++c)
                        if ((c >> axis) & 1) {
                            ASSERT_EQ((r >> c) & 1, (u >> (c ^ (1 << axis))) & 1) << "crack at " << x << " " << y << " " << z;
                        }
                }
            }
    std::cout << "[ corner refinement ] " << surface << " surface cubes, irregular " << irregularRaw << " raw, "
              << irregularRefined << " refined; " << flippedCorners << " corner flips seen\n";
    EXPECT_GT(flippedCorners, 0u);
    EXPECT_LT(irregularRefined, irregularRaw);
}

TEST(CornerRefinement, UnobservedCubesHaveNoSurface) {
    float d[kWindowSize];
    bool observed[kWindowSize];
    for (int w = 0; w < kWindowSize; ++w) {
        d[w] = (w / 16 == 1) ? -0.01f : 0.01f;
        observed[w] = true;
    }
    EXPECT_EQ(refinedCubeType(d, observed, 0.5f), 0x0F);
    observed[windowIndex(1, 1, 1)] = false;
    EXPECT_EQ(refinedCubeType(d, observed, 0.5f), 0);
}


// decide_mesh_signs' word decision (shaders_comp/retype/sign_window.h, run here by refinedSignWord) against the
// specification: on random neighbourhoods of 3x3x3 blocks (some absent, some corners unobserved), every corner of
// the centre block gets exactly refinedCornerInside() of its 27-corner window, read across the block faces.
TEST(CornerRefinement, MaskWordDecisionEqualsTheCornerRuleOnRandomBlocks) {
    constexpr float kEpsilon = 0.5f;
    std::mt19937 rng(12345);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    uint64_t corners = 0, flipped = 0, evaluatedTotal = 0;
    for (int trial = 0; trial < 600; ++trial) {
        // The field over 24^3 corners (global position g in [0, 24)): a tilted plane or sphere with noise (so that
        // near corners and bumps occur), or random signs with every corner near (every window pattern).
        const int kind = trial % 3;
        const float nx = unit(rng), ny = unit(rng), nz = 2.0f + unit(rng), c = 12.0f + 2.0f * unit(rng);
        const float noise = 0.2f + 0.6f * std::abs(unit(rng));
        const float unobservedShare = trial % 4 == 0 ? 0.0f : 0.05f * std::abs(unit(rng));
        std::vector<float> sdf(24 * 24 * 24), weight(sdf.size());
        for (int z = 0; z < 24; ++z)
            for (int y = 0; y < 24; ++y)
                for (int x = 0; x < 24; ++x) {
                    const size_t i = size_t(x + 24 * (y + 24 * z));
                    float d;
                    if (kind == 0) d = (nx * (x - 12) + ny * (y - 12) + nz * z - nz * c) / 2.0f + noise * unit(rng);
                    else if (kind == 1) d = std::sqrt(float((x - 12) * (x - 12) + (y - 12) * (y - 12) + (z - 12) * (z - 12))) - c / 2.0f + noise * unit(rng);
                    else d = unit(rng) < 0.0f ? -0.25f : 0.25f;
                    sdf[i] = d;
                    weight[i] = (unit(rng) * 0.5f + 0.5f) < unobservedShare ? 0.0f : 1.0f + float(trial % 5);
                }
        auto at = [&](int x, int y, int z) { return size_t(x + 24 * (y + 24 * z)); };
        std::array<TsdfMasks, 27> masks;
        std::array<const TsdfMasks*, 27> blocks{};
        std::array<bool, 27> present{};
        for (int b = 0; b < 27; ++b) {
            present[size_t(b)] = b == 13 || (unit(rng) * 0.5f + 0.5f) > 0.1f;
            const int bx = b % 3, by = (b / 3) % 3, bz = b / 9;
            float s[512], w[512];
            for (int l = 0; l < 512; ++l) {
                const size_t i = at(8 * bx + l % 8, 8 * by + (l / 8) % 8, 8 * bz + l / 64);
                s[l] = sdf[i];
                w[l] = weight[i];
            }
            masks[size_t(b)] = tsdfMasks(s, w, 1.0f, kEpsilon);
            if (present[size_t(b)]) blocks[size_t(b)] = &masks[size_t(b)];
        }
        for (uint32_t word = 0; word < 16; ++word) {
            uint32_t evaluated = 0;
            const uint32_t signs = refinedSignWord(blocks, word, &evaluated);
            evaluatedTotal += evaluated;
            for (uint32_t bit = 0; bit < 32; ++bit) {
                const int local = int(word * 32 + bit);
                const int gx = 8 + local % 8, gy = 8 + (local / 8) % 8, gz = 8 + local / 64;
                float d[kCornerWindowSize];
                bool observed[kCornerWindowSize];
                for (int w = 0; w < kCornerWindowSize; ++w) {
                    const int x = gx + w % 3 - 1, y = gy + (w / 3) % 3 - 1, z = gz + w / 9 - 1;
                    const bool blockPresent = present[size_t(x / 8 + 3 * (y / 8) + 9 * (z / 8))];
                    d[w] = blockPresent ? sdf[at(x, y, z)] : 0.0f;
                    observed[w] = blockPresent && weight[at(x, y, z)] >= 1.0f;
                }
                const bool expected = refinedCornerInside(d, observed, kEpsilon);
                ASSERT_EQ(((signs >> bit) & 1u) != 0u, expected)
                    << "trial " << trial << " word " << word << " bit " << bit << " (corner " << gx - 8 << ", " << gy - 8 << ", " << gz - 8 << ")";
                ++corners;
                flipped += expected != (d[cornerWindowIndex(0, 0, 0)] < 0.0f);
            }
        }
    }
    std::cout << corners << " corners, " << flipped << " flipped, " << evaluatedTotal << " decided bit by bit\n";
    EXPECT_GT(flipped, 1000u);
}

// The same rule on single windows: every 27-bit pattern of a near corner whose window is all observed, sampled.
TEST(CornerRefinement, MaskWordDecisionEqualsTheCornerRuleOnRandomWindows) {
    std::mt19937 rng(777);
    uint64_t flips = 0;
    for (int trial = 0; trial < 200000; ++trial) {
        const uint32_t pattern = rng() & ((1u << 27) - 1);
        // One block holding the window at corner (3, 2, 5) (inside the block, word 10 bit 19) and its
        // neighbourhood; all other corners far and observed.
        float s[512], w[512];
        for (int l = 0; l < 512; ++l) { s[l] = 1.0f; w[l] = 1.0f; }
        float d[kCornerWindowSize];
        bool observed[kCornerWindowSize];
        for (int k = 0; k < kCornerWindowSize; ++k) {
            const int x = 3 + k % 3 - 1, y = 2 + (k / 3) % 3 - 1, z = 5 + k / 9 - 1;
            d[k] = ((pattern >> k) & 1u) ? -0.1f : 0.1f;
            observed[k] = true;
            s[x + 8 * (y + 8 * z)] = d[k];
        }
        const TsdfMasks m = tsdfMasks(s, w, 1.0f, 0.5f);
        std::array<const TsdfMasks*, 27> blocks{};
        blocks[13] = &m;
        const int local = 3 + 8 * (2 + 8 * 5);
        const bool got = ((refinedSignWord(blocks, uint32_t(local / 32)) >> (local % 32)) & 1u) != 0u;
        const bool expected = refinedCornerInside(d, observed, 0.5f);
        ASSERT_EQ(got, expected) << "pattern " << pattern;
        flips += expected != (d[13] < 0.0f);
    }
    EXPECT_GT(flips, 100u);
}

}  // namespace
}  // namespace vkmesh

namespace vkmesh {
namespace {

// edgeCrossing (docs/REFINEMENT.md, "Vertices"): unrefined, the zero crossing kept 1/1024 off the ends; refined,
// never on a corner, so that the vertices of two edges that meet at a corner never share a position.
TEST(EdgeCrossing, RefinedVerticesStayOffTheCorners) {
    const float flippedMargin = 1.0f / float(gpu::FLIPPED_EDGE_MARGIN_INVERSE);
    const float margin = 1.0f / float(gpu::REFINED_EDGE_MARGIN_INVERSE);
    // Unrefined: the crossing, kept 1/1024 off the ends too (d = 0 exactly is common with integer sums:
    // shared_layout.h "A TSDF corner"), and no flipped corner to stop before.
    EXPECT_EQ(edgeCrossing(-0.25f, 0.75f, false), 0.25f);
    EXPECT_EQ(edgeCrossing(0.0f, -1.0f, false), margin);     // d = 0 on the low corner: next to it, not on it
    EXPECT_EQ(edgeCrossing(0.5f, 0.25f, false), 1.0f - margin);
    EXPECT_EQ(edgeCrossing(0.3f, 0.3f, false), 0.5f);
    // Refined: a flipped edge's vertex stops next to the flipped corner, whichever end it is.
    EXPECT_EQ(edgeCrossing(0.5f, 0.25f, true), 1.0f - flippedMargin);
    EXPECT_EQ(edgeCrossing(0.25f, 0.5f, true), flippedMargin);
    EXPECT_EQ(edgeCrossing(-0.25f, -0.5f, true), flippedMargin);
    EXPECT_EQ(edgeCrossing(0.3f, 0.3f, true), 0.5f);
    // A crossing on a corner or a hair from it is kept off the corner; one inside the margins is unchanged.
    EXPECT_EQ(edgeCrossing(0.0f, -1.0f, true), margin);
    EXPECT_EQ(edgeCrossing(-1e-9f, 1.0f, true), margin);
    EXPECT_EQ(edgeCrossing(-1.0f, 0.0f, true), 1.0f - margin);
    EXPECT_EQ(edgeCrossing(-0.25f, 0.75f, true), 0.25f);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> value(-1.0f, 1.0f);
    for (int i = 0; i < 100000; ++i) {
        float lo = value(rng), hi = value(rng);
        if (i % 7 == 0) lo = 0.0f;
        if (i % 11 == 0) hi = std::ldexp(hi, -30);
        const float plain = edgeCrossing(lo, hi, false), refined = edgeCrossing(lo, hi, true);
        ASSERT_GE(refined, margin) << lo << " " << hi;
        ASSERT_LE(refined, 1.0f - margin) << lo << " " << hi;
        ASSERT_TRUE(plain >= margin && plain <= 1.0f - margin);
        // Where the corners differ in sign and the crossing is inside the margins, refinement leaves it alone.
        if ((lo < 0.0f) != (hi < 0.0f) && plain >= margin && plain <= 1.0f - margin) ASSERT_EQ(refined, plain);
    }
    // Positions: the vertices of the 6 edges at a corner (3 leaving it, 3 arriving), each as near the corner as
    // a refined mesh allows, are 6 distinct points, also far from the origin (grid coordinates up to 2^13).
    for (float corner : {0.0f, 1.0f, 37.0f, 4095.0f, 8191.0f}) {
        std::set<std::array<float, 3>> points;
        for (int axis = 0; axis < 3; ++axis) {
            std::array<float, 3> leaving{corner, corner, corner}, arriving{corner, corner, corner};
            leaving[axis] = corner + margin;
            arriving[axis] = (corner - 1.0f) + (1.0f - margin);
            points.insert(leaving);
            points.insert(arriving);
        }
        EXPECT_EQ(points.size(), 6u) << "corner at " << corner;
    }
}

}  // namespace
}  // namespace vkmesh
