#version 460
// Stage 1 of a frame (paper §V.A): every valid pixel (of every allocationStride-th row and column, and only in
// the tiles allocate_tiles did not cover) walks the blocks that its truncation band crosses
// (a 3D DDA in block units from depth d - trunc to d + trunc along the pixel's ray), inserts their keys
// into the spatial hash, and appends each block touched for the first time this frame to the touched
// list. Blocks get pool memory in the next stage (assign_blocks): here a key is only claimed. A frame being
// de-integrated (framePose.deintegrate) claims nothing: its band walk finds the blocks it was fused into that
// still hold observations (a block whose last observation another de-integration took out was freed; the band
// may also cross blocks where the frame updated no corner).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/frame_lists.glsl"
#include "structure/depth_input.glsl"

layout(local_size_x = WG_PIXELS_X, local_size_y = WG_PIXELS_Y) in;
layout(constant_id = 0) const uint ALLOCATE_DIRECTION = FUSE_BY_FRAME;   // shared_layout.h, FUSE_INTEGRATE

#include "allocate/block_visits.glsl"

// Walks the band of one sampled pixel.
void walkPixel(uvec2 pixel, uvec2 size, inout uint valid, inout uint truncated) {
    float d = depthAt(pixel.y * size.x + pixel.x);
    if (d >= frame.minDepth && d <= frame.maxDepth) {
        ++valid;
        // Camera-frame ray through the pixel, scaled so that its z is 1.
        precise vec3 ray = vec3((float(pixel.x) - frame.intrinsics.z) / frame.intrinsics.x,
                                (float(pixel.y) - frame.intrinsics.w) / frame.intrinsics.y, 1.0);
        float nearZ = max(d - params.truncation, frame.minDepth * 0.5);
        float farZ = d + params.truncation;
        float blockSize = params.voxelSize * float(BLOCK_SIDE);
        precise vec3 a = transformPoint(framePose.cameraToWorld, ray * nearZ) / blockSize;
        precise vec3 b = transformPoint(framePose.cameraToWorld, ray * farZ) / blockSize;

        // Amanatides & Woo traversal from a to b, parameter t in [0, 1]. Written without dynamic
        // component indexing (v[axis]), which llvmpipe turns into slow scratch memory.
        precise vec3 dir = b - a;
        vec3 fa = floor(a);
        ivec3 cell = ivec3(fa);
        ivec3 last = ivec3(floor(b));
        ivec3 stepDir = ivec3(sign(dir));
        precise vec3 adir = abs(dir);
        precise vec3 dist = mix(a - fa, fa + 1.0 - a, greaterThan(dir, vec3(0.0)));
        bvec3 still = equal(dir, vec3(0.0));
        precise vec3 tMax = mix(dist / adir, vec3(1e30), still);
        precise vec3 tDelta = mix(1.0 / adir, vec3(1e30), still);
        bool cut = true;
        for (uint s = 0u; s < RAY_MAX_BLOCKS; ++s) {
            visitBlock(cell);
            if (cell == last) { cut = false; break; }
            if (tMax.x <= tMax.y && tMax.x <= tMax.z) {
                if (tMax.x > 1.0) { cut = false; break; }
                cell.x += stepDir.x;
                tMax.x += tDelta.x;
            } else if (tMax.y <= tMax.z) {
                if (tMax.y > 1.0) { cut = false; break; }
                cell.y += stepDir.y;
                tMax.y += tDelta.y;
            } else {
                if (tMax.z > 1.0) { cut = false; break; }
                cell.z += stepDir.z;
                tMax.z += tDelta.z;
            }
        }
        if (cut) ++truncated;
    }
}

void main() {
    uvec2 size = frameImageSize();
    uint valid = 0u, truncated = 0u;
    if (!frameSkipped()) {
        // This invocation's column of ALLOC_COLUMN sampled pixels, top down: consecutive pixels are neighbours
        // and share most blocks, while the lanes of a subgroup read neighbouring pixels of one row (on lavapipe
        // a column is 0.67 x the allocation time of the same A/B against 0.80 x for a 4 x 4 tile walked back
        // and forth, with 30 % more hash requests). The column spans two allocation tiles; the rows of a tile
        // whose slab allocate_tiles claimed are skipped, by a loop with no row to run (llvmpipe would run the
        // body of an `if` under a mask).
        uvec2 firstSample = gl_GlobalInvocationID.xy * uvec2(1u, ALLOC_COLUMN);
        uvec2 samples = (size + params.allocationStride - 1u) / params.allocationStride;
        uint tilesX = (samples.x + ALLOC_TILE - 1u) / ALLOC_TILE;
        for (uint part = 0u; part < ALLOC_COLUMN / ALLOC_TILE; ++part) {
            uvec2 partFirst = firstSample + uvec2(0u, part * ALLOC_TILE);
            bool covered = params.allocationTiles != 0u && all(lessThan(partFirst, samples)) &&
                           tileCovered[(partFirst.y / ALLOC_TILE) * tilesX + partFirst.x / ALLOC_TILE] != 0u;
            uint rows = covered ? 0u : ALLOC_TILE;
            for (uint row = 0u; row < rows; ++row) {
                uvec2 pixel = (partFirst + uvec2(0u, row)) * params.allocationStride;
                if (all(lessThan(pixel, size))) walkPixel(pixel, size, valid, truncated);
            }
        }
    }
    ADD_COUNTER(validPixels, valid);
    ADD_COUNTER(blockRequests, requests);
    ADD_COUNTER(blocksFound, found);
    ADD_COUNTER(blocksInserted, inserted);
    ADD_COUNTER(hashFull, full);
    ADD_COUNTER(outOfRange, outOfRange);
    ADD_COUNTER(outsideRadius, outsideRadius);
    ADD_COUNTER(blocksShared, repeated);
    ADD_COUNTER(rayTruncated, truncated);
}
