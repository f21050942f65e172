// The CPU twin of shaders_comp/structure/voxel_color.glsl (docs/COLOR.md): a corner's colour word, how fusion
// folds a pixel's colour into it, and a vertex's colour from its edge's corners. Same float operations in the
// same order as the shader (built with -ffp-contract=off), so the CPU reference matches the GPU bit for bit.
#pragma once

#include <algorithm>
#include <bit>
#include <array>
#include <cmath>
#include <cstdint>

#include "shared_layout.h"

namespace vkmesh {

using ColorChannels = std::array<float, 3>;

inline ColorChannels unpackVoxelColor(uint32_t word) {
    const uint32_t m = gpu::VOXEL_COLOR_CHANNEL_MASK, bits = gpu::VOXEL_COLOR_BITS;
    return {float(word & m), float((word >> bits) & m), float((word >> (2 * bits)) & m)};
}

inline uint32_t packVoxelColor(uint32_t r, uint32_t g, uint32_t b) {
    const uint32_t bits = gpu::VOXEL_COLOR_BITS;
    return r | (g << bits) | (b << (2 * bits)) | gpu::VOXEL_COLOR_SET;
}

inline bool hasVoxelColor(uint32_t word) { return (word & gpu::VOXEL_COLOR_SET) != 0; }

// The corner's 8-bit colour (the stored value / 4, rounded).
inline std::array<uint8_t, 3> voxelColor8(uint32_t word) {
    const ColorChannels c = unpackVoxelColor(word);
    std::array<uint8_t, 3> out{};
    for (int i = 0; i < 3; ++i) out[i] = uint8_t(std::min(std::floor(c[i] * 0.25f + 0.5f), 255.0f));
    return out;
}

inline float colorDither(const std::array<int, 3>& corner, uint32_t salt) {
    const uint32_t x = uint32_t(corner[0]), y = uint32_t(corner[1]), z = uint32_t(corner[2]);
    uint32_t h = (x * 0x9E3779B1u) ^ (y * 0x85EBCA77u) ^ (z * 0xC2B2AE3Du) ^ (salt * 0x27D4EB2Fu);
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return float(h >> 8) * (1.0f / 16777216.0f);
}

// colorMode / colorRecency: gpu::VolumeParamsGpu's; corner: the corner's global grid position (block * 8 +
// local); with the weight before and the distance after the update, it seeds the dither.
inline uint32_t foldVoxelColor(uint32_t old, float oldWeight, float newSdf, const uint8_t rgb[3], const std::array<int, 3>& corner,
                               uint32_t colorMode, float colorRecency) {
    const uint32_t scale = gpu::VOXEL_COLOR_SCALE;
    if (!hasVoxelColor(old) || oldWeight == 0.0f) return packVoxelColor(rgb[0] * scale, rgb[1] * scale, rgb[2] * scale);
    const ColorChannels prev = unpackVoxelColor(old);
    const float dither = colorDither(corner, std::bit_cast<uint32_t>(newSdf) + std::bit_cast<uint32_t>(oldWeight) * 0x2545F491u);
    uint32_t q[3];
    for (int i = 0; i < 3; ++i) {
        const float target = float(rgb[i] * scale);
        float mixed;
        if (colorMode == gpu::COLOR_MODE_RECENT) mixed = prev[i] + (target - prev[i]) * colorRecency;
        else mixed = (prev[i] * oldWeight + target) / (oldWeight + 1.0f);
        const float dithered = mixed + dither;
        q[i] = uint32_t(std::min(std::floor(dithered), float(255 * scale)));
    }
    return packVoxelColor(q[0], q[1], q[2]);
}

// The corner's colour word after the observation `rgb` is taken out again (de-integration): oldWeight >= 2 is
// the weight before, newSdf the distance after. The exponential mode cannot be undone: its word stays.
inline uint32_t unfoldVoxelColor(uint32_t old, float oldWeight, float newSdf, const uint8_t rgb[3], const std::array<int, 3>& corner,
                                 uint32_t colorMode) {
    const uint32_t scale = gpu::VOXEL_COLOR_SCALE;
    if (!hasVoxelColor(old) || colorMode == gpu::COLOR_MODE_RECENT) return old;
    const ColorChannels prev = unpackVoxelColor(old);
    const float dither = colorDither(corner, std::bit_cast<uint32_t>(newSdf) + std::bit_cast<uint32_t>(oldWeight) * 0x2545F491u);
    uint32_t q[3];
    for (int i = 0; i < 3; ++i) {
        const float target = float(rgb[i] * scale);
        const float unmixed = (prev[i] * oldWeight - target) / (oldWeight - 1.0f);
        const float dithered = unmixed + dither;
        q[i] = uint32_t(std::clamp(std::floor(dithered), 0.0f, float(255 * scale)));
    }
    return packVoxelColor(q[0], q[1], q[2]);
}

// A vertex's colour (Vertex::color, RGBA8, alpha 255) from its edge's corner colours, interpolated at its
// position's t along the edge (edgeCrossing in core/refinement.h); 0 (alpha 0) when neither has a colour.
inline uint32_t vertexColorOnEdge(uint32_t lo, uint32_t hi, float t) {
    const bool hasLo = hasVoxelColor(lo), hasHi = hasVoxelColor(hi);
    if (!hasLo && !hasHi) return 0;
    const ColorChannels a = unpackVoxelColor(hasLo ? lo : hi), b = unpackVoxelColor(hasHi ? hi : lo);
    uint32_t out = 255u << 24;
    for (int i = 0; i < 3; ++i) {
        const float c = a[i] + (b[i] - a[i]) * t;
        const float rounded = c * (1.0f / float(gpu::VOXEL_COLOR_SCALE)) + 0.5f;
        out |= uint32_t(std::min(std::floor(rounded), 255.0f)) << (8 * i);
    }
    return out;
}

// Vertex::color's channels and whether it has a colour (alpha 255).
inline std::array<uint8_t, 3> vertexColorRgb(uint32_t color) {
    return {uint8_t(color & 0xFF), uint8_t((color >> 8) & 0xFF), uint8_t((color >> 16) & 0xFF)};
}
inline bool vertexHasColor(uint32_t color) { return (color >> 24) != 0; }

}  // namespace vkmesh
