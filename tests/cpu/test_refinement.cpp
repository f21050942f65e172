// refineType (docs/REFINEMENT.md, paper §V.F): the regular-type table and the pure function the CPU reference
// mesher and the GPU (shaders_comp/structure/cube_access.glsl) both apply.
#include "core/refinement.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>
#include <set>

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
