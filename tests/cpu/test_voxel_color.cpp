// The colour word of a TSDF corner and its update rules (src/core/voxel_color.h, the twin of
// shaders_comp/structure/voxel_color.glsl): the running average does not stall at high weight, is unbiased,
// the recent mode follows a change, and a vertex interpolates its edge's colours.
#include <gtest/gtest.h>

#include <cmath>

#include "core/refinement.h"
#include "core/voxel_color.h"

namespace vkmesh {
namespace {

constexpr uint32_t kAverage = gpu::COLOR_MODE_AVERAGE, kRecent = gpu::COLOR_MODE_RECENT;

// Folds `frames` observations produced by `observe(frame)` into one corner with the TSDF's weights (+1 per
// frame, capped at 255), as fusion does; returns the stored channel values (4 x 8-bit).
template <typename Observe>
ColorChannels foldSequence(int frames, uint32_t mode, float recency, Observe observe, std::array<int, 3> corner = {3, -7, 11}) {
    uint32_t word = 0;
    float weight = 0;
    for (int f = 1; f <= frames; ++f) {
        const std::array<uint8_t, 3> rgb = observe(f);
        word = foldVoxelColor(word, weight, 0.01f * float(f % 7), rgb.data(), corner, mode, recency);
        weight = std::min(weight + 1.0f, 255.0f);
    }
    EXPECT_TRUE(hasVoxelColor(word));
    return unpackVoxelColor(word);
}

TEST(VoxelColor, FirstObservationIsStoredExactly) {
    const uint8_t rgb[3] = {0, 128, 255};
    const uint32_t word = foldVoxelColor(0, 0.0f, 0.0f, rgb, {0, 0, 0}, kAverage, 0.2f);
    EXPECT_TRUE(hasVoxelColor(word));
    EXPECT_EQ(voxelColor8(word), (std::array<uint8_t, 3>{0, 128, 255}));
    // A corner that lost its weight (recycled, or a block handed out again) starts afresh.
    const uint8_t other[3] = {10, 20, 30};
    EXPECT_EQ(voxelColor8(foldVoxelColor(word, 0.0f, 0.0f, other, {0, 0, 0}, kAverage, 0.2f)), (std::array<uint8_t, 3>{10, 20, 30}));
}

TEST(VoxelColor, ConstantColourStaysExact) {
    const ColorChannels c = foldSequence(300, kAverage, 0.2f, [](int) { return std::array<uint8_t, 3>{17, 200, 93}; });
    EXPECT_EQ(c[0], 68.0f);
    EXPECT_EQ(c[1], 800.0f);
    EXPECT_EQ(c[2], 372.0f);
}

// Alternating 100 and 101 averages to 100.5; an 8-bit running average rounded to nearest would stay at the
// first value once the weight passes a few frames. The dithered 10-bit average lands within a quarter level.
TEST(VoxelColor, RunningAverageDoesNotStallAndIsUnbiased) {
    double sum = 0;
    const int corners = 200;
    for (int k = 0; k < corners; ++k) {
        const ColorChannels c = foldSequence(
            200, kAverage, 0.2f, [](int f) { return std::array<uint8_t, 3>{uint8_t(100 + f % 2), 50, 50}; }, {k, 2 * k, -k});
        sum += c[0] / 4.0;
        EXPECT_NEAR(c[0] / 4.0, 100.5, 1.0);
    }
    EXPECT_NEAR(sum / corners, 100.5, 0.1);
    // A change late in the sequence still moves the average (weight 255 reached).
    const ColorChannels late = foldSequence(400, kAverage, 0.2f, [](int f) {
        return std::array<uint8_t, 3>{uint8_t(f <= 300 ? 100 : 140), 0, 0};
    });
    EXPECT_GT(late[0] / 4.0, 105.0);   // 100 frames of 140 at weight 255: 140 - 40 (255/256)^100 = 113
    EXPECT_LT(late[0] / 4.0, 115.0);
}

TEST(VoxelColor, RecentModeFollowsAChange) {
    const ColorChannels c = foldSequence(60, kRecent, 0.2f, [](int f) {
        return std::array<uint8_t, 3>{uint8_t(f <= 40 ? 50 : 200), 0, 0};
    });
    // 20 frames at 0.2: 1 - 0.8^20 = 99 % of the way.
    EXPECT_NEAR(c[0] / 4.0, 200.0, 3.0);
    const ColorChannels avg = foldSequence(60, kAverage, 0.2f, [](int f) {
        return std::array<uint8_t, 3>{uint8_t(f <= 40 ? 50 : 200), 0, 0};
    });
    EXPECT_NEAR(avg[0] / 4.0, 100.0, 2.0);   // the plain average remembers all 60
}

TEST(VoxelColor, VertexInterpolatesItsEdge) {
    const uint32_t black = packVoxelColor(0, 0, 0), white = packVoxelColor(1020, 1020, 1020);
    auto rgb = [](uint32_t c) { return vertexColorRgb(c); };
    auto at = [&](float dLo, float dHi, bool refined = false) { return rgb(vertexColorOnEdge(black, white, edgeCrossing(dLo, dHi, refined))); };
    // Zero crossing at the low corner, the middle, the high corner.
    EXPECT_EQ(at(0.0f, 1.0f), (std::array<uint8_t, 3>{0, 0, 0}));
    EXPECT_EQ(at(-0.5f, 0.5f), (std::array<uint8_t, 3>{128, 128, 128}));
    EXPECT_EQ(at(-1.0f, 0.0f), (std::array<uint8_t, 3>{255, 255, 255}));
    // Extrapolated positions (refinement) stop at the edge's end, or 1/8 of the edge before it in a refined mesh.
    EXPECT_EQ(at(0.5f, 0.25f), (std::array<uint8_t, 3>{255, 255, 255}));
    const uint8_t nearWhite = uint8_t(std::floor(1020.0 * (1.0 - 1.0 / gpu::FLIPPED_EDGE_MARGIN_INVERSE) / 4.0 + 0.5));
    EXPECT_LT(nearWhite, 255);
    EXPECT_EQ(at(0.5f, 0.25f, true), (std::array<uint8_t, 3>{nearWhite, nearWhite, nearWhite}));
    EXPECT_TRUE(vertexHasColor(vertexColorOnEdge(black, white, 0.0f)));
    // One corner without colour: the other's; none: no colour (alpha 0).
    EXPECT_EQ(rgb(vertexColorOnEdge(0, white, 0.5f)), (std::array<uint8_t, 3>{255, 255, 255}));
    EXPECT_FALSE(vertexHasColor(vertexColorOnEdge(0, 0, 0.5f)));
}

TEST(VoxelColor, DitherIsInUnitIntervalAndVariesWithPositionAndFrame) {
    double sum = 0;
    int distinct = 0;
    float last = -1;
    for (int i = 0; i < 1000; ++i) {
        const float d = colorDither({i, -i, 3}, uint32_t(i / 10));
        EXPECT_GE(d, 0.0f);
        EXPECT_LT(d, 1.0f);
        sum += d;
        distinct += d != last;
        last = d;
    }
    EXPECT_NEAR(sum / 1000, 0.5, 0.05);
    EXPECT_GT(distinct, 990);
}

}  // namespace
}  // namespace vkmesh
