// Colour at the TSDF corners (docs/COLOR.md): how fusion folds a pixel's colour into a corner's, and how a
// vertex takes its colour from the two corners of its edge. src/core/voxel_color.h is the CPU twin of every
// function here, with the same float operations in the same order (the tests compare them bit for bit).
#ifndef VKMESH_VOXEL_COLOR_GLSL
#define VKMESH_VOXEL_COLOR_GLSL
#include "structure/frame.glsl"

vec3 unpackVoxelColor(uint word) {
    return vec3(uvec3(word, word >> VOXEL_COLOR_BITS, word >> (2u * VOXEL_COLOR_BITS)) & VOXEL_COLOR_CHANNEL_MASK);
}

uint packVoxelColor(uvec3 q) {
    return q.x | (q.y << VOXEL_COLOR_BITS) | (q.z << (2u * VOXEL_COLOR_BITS)) | VOXEL_COLOR_SET;
}

// A value in [0, 1) from the corner's grid position and a salt that changes with every observation (a fixed
// integer hash), so that rounding a running average to the stored precision is unbiased, yet every run (and
// the CPU reference) rounds alike. Neither input depends on thread scheduling (the corner's place in the pool
// would) or on frame numbers (a frame run again after growing a capacity gets a new one): the colour is a
// function of the frames fused, whatever the capacities.
float colorDither(ivec3 corner, uint salt) {
    uvec3 c = uvec3(corner);
    uint h = (c.x * 0x9E3779B1u) ^ (c.y * 0x85EBCA77u) ^ (c.z * 0xC2B2AE3Du) ^ (salt * 0x27D4EB2Fu);
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return float(h >> 8) * (1.0 / 16777216.0);
}

// The corner's colour word after one more observation `rgb` (8-bit), `oldWeight` being the corner's TSDF
// weight before this frame's update and `newSdf` its distance after it (with the weight, the dither's salt):
// the running average with the TSDF's weights, or the exponential one.
// A corner without a colour yet, or without weight (a block handed out again, or emptied by recycling), takes
// the pixel's.
uint foldVoxelColor(uint old, float oldWeight, float newSdf, uvec3 rgb, ivec3 corner) {
    vec3 target = vec3(rgb * VOXEL_COLOR_SCALE);
    if ((old & VOXEL_COLOR_SET) == 0u || oldWeight == 0.0) return packVoxelColor(rgb * VOXEL_COLOR_SCALE);
    vec3 prev = unpackVoxelColor(old);
    precise vec3 mixed;
    if (params.colorMode == COLOR_MODE_RECENT) {
        mixed = prev + (target - prev) * params.colorRecency;
    } else {
        mixed = (prev * oldWeight + target) / (oldWeight + 1.0);
    }
    precise vec3 dithered = mixed + colorDither(corner, floatBitsToUint(newSdf) + floatBitsToUint(oldWeight) * 0x2545F491u);
    return packVoxelColor(uvec3(min(floor(dithered), vec3(float(255u * VOXEL_COLOR_SCALE)))));
}

// The corner's colour word after the observation `rgb` is taken out again (de-integration), `oldWeight` being
// the weight before (>= 2: the corner keeps an observation) and `newSdf` the distance after: the running
// average without it, rounded with the same dither. Not exact (each fold and unfold rounds to a quarter of an
// 8-bit level; docs/CORRECTION.md gives the bound), and the exponential mode cannot be undone at all: its
// colour is left as it is, and the frame's re-integration folds the colour in again.
uint unfoldVoxelColor(uint old, float oldWeight, float newSdf, uvec3 rgb, ivec3 corner) {
    if ((old & VOXEL_COLOR_SET) == 0u || params.colorMode == COLOR_MODE_RECENT) return old;
    vec3 target = vec3(rgb * VOXEL_COLOR_SCALE);
    vec3 prev = unpackVoxelColor(old);
    precise vec3 unmixed = (prev * oldWeight - target) / (oldWeight - 1.0);
    precise vec3 dithered = unmixed + colorDither(corner, floatBitsToUint(newSdf) + floatBitsToUint(oldWeight) * 0x2545F491u);
    return packVoxelColor(uvec3(clamp(floor(dithered), vec3(0.0), vec3(float(255u * VOXEL_COLOR_SCALE)))));
}

// A vertex's colour (Vertex::color, RGBA8, alpha 255) from the colours of its edge's corners, interpolated
// at its position's s along the edge (edgeCrossing in cube_access.glsl); 0 (alpha 0) when neither corner has a colour.
uint vertexColorOnEdge(uint lo, uint hi, float t) {
    bool hasLo = (lo & VOXEL_COLOR_SET) != 0u, hasHi = (hi & VOXEL_COLOR_SET) != 0u;
    if (!hasLo && !hasHi) return 0u;
    vec3 a = unpackVoxelColor(hasLo ? lo : hi), b = unpackVoxelColor(hasHi ? hi : lo);
    precise vec3 c = a + (b - a) * t;
    precise vec3 rounded = c * (1.0 / float(VOXEL_COLOR_SCALE)) + 0.5;
    uvec3 o = uvec3(min(floor(rounded), vec3(255.0)));
    return o.x | (o.y << 8) | (o.z << 16) | (255u << 24);
}
#endif
