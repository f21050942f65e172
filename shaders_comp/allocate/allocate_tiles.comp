#version 460
// Stage 1 of a frame, by tiles (with VolumeParams::allocationTiles, before allocate_blocks): one invocation per tile
// of ALLOC_TILE x ALLOC_TILE sampled pixels fits a plane to the tile's depths and, where the plane fits, claims every
// block that the slab around it may cross, a superset of the blocks the tile's pixels' band walks would visit
// (allocate_blocks), for a fraction of the walks' cost. A tile the plane does not fit (a depth edge, too few valid
// depths, a surface seen edge-on) is left to allocate_blocks, which walks its pixels one by one; a tile without
// any valid depth is covered, as it has nothing to walk. tileCovered[tile] says which (rewritten every frame). One
// invocation per tile, not a workgroup: on lavapipe a workgroup per tile with subgroup and shared-memory sums took
// 5.5 ms a frame on the synthetic room, this 0.6.
//
// Why the slab covers the bands: a sampled pixel with depth d in [minDepth, maxDepth] walks its ray (x', y', 1)
// (camera frame) from z = d - trunc to d + trunc. The plane z = a x + b y + g (camera frame, least squares over
// the tile's valid samples) meets that ray at z_p = g / D with D = 1 - a x' - b y', and |d - z_p| <= r, the
// largest residual over the tile, so the band lies in z_p +- (trunc + r). Along the ray, the planes
// z - a x - b y = g +- m lie at (g +- m) / D = z_p +- m / D, so with m >= (trunc + r) |D| for every ray of the
// tile (D is linear in x', y' and of one sign over the tile: its largest |D| is at a corner of the box of the
// tile's rays) every band lies between them, and inside the pyramid of that box. A block is claimed unless it lies
// wholly outside one of those six planes.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/frame_lists.glsl"
#include "structure/depth_input.glsl"

layout(local_size_x = WG_PIXELS_X, local_size_y = WG_PIXELS_Y) in;   // tiles
layout(constant_id = 0) const uint ALLOCATE_DIRECTION = FUSE_BY_FRAME;   // shared_layout.h, FUSE_INTEGRATE

#include "allocate/block_visits.glsl"

vec2 rayOf(uvec2 pixel) {
    precise vec2 ray = vec2((float(pixel.x) - frame.intrinsics.z) / frame.intrinsics.x, (float(pixel.y) - frame.intrinsics.w) / frame.intrinsics.y);
    return ray;
}

// Whether the box [c, c + 1] (block units) lies wholly on the negative side of the plane n . q = o, with a margin.
bool boxOutside(vec3 c, vec3 n, float o) {
    precise float high = n.x * c.x + n.y * c.y + n.z * c.z + max(n.x, 0.0) + max(n.y, 0.0) + max(n.z, 0.0);
    precise float bound = o - ALLOC_SLAB_MARGIN * (abs(n.x) + abs(n.y) + abs(n.z));
    return high < bound;
}

// A camera-frame plane n . p = o as a plane in world block units (p_world = blockSize q).
vec4 planeToBlocks(vec3 n, float o, vec3 origin, float blockSize) {
    precise vec3 nw = transformPoint(framePose.cameraToWorld, n) - origin;   // the rotation alone
    precise float ow = (o + (nw.x * origin.x + nw.y * origin.y + nw.z * origin.z)) / blockSize;
    return vec4(nw, ow);
}

// The plane's normal through two rays of the pyramid (cross(e, f), written out for the CPU twin's order).
vec3 sideNormal(vec2 e, vec2 f) {
    precise vec3 n = vec3(e.y - f.y, f.x - e.x, e.x * f.y - f.x * e.y);
    return n;
}

// Claims the blocks of the tile's slab; false (nothing claimed) where the tile is left to allocate_blocks. Every
// float operation is `precise` and in the order of the CPU twin (cpu/reference_allocation.cpp), which decides the
// same tiles and blocks bit for bit.
bool walkSlab(uvec2 first, uvec2 last, uvec2 size, inout uint valid) {
    // Least squares z = a x + b y + g (camera frame) over the tile's valid samples, from moments about the first
    // sample's point (any plane would do for the cover: the residual below is measured from the plane found).
    precise vec3 origin0 = vec3(rayOf(first), 1.0) * depthAt(first.y * size.x + first.x);
    uint n = 0u;
    precise vec3 s1 = vec3(0.0);
    precise float sxx = 0.0, sxy = 0.0, syy = 0.0, sxz = 0.0, syz = 0.0;
    for (uint j = 0u; j < ALLOC_TILE * ALLOC_TILE; ++j) {
        uvec2 pixel = first + uvec2(j % ALLOC_TILE, j / ALLOC_TILE) * params.allocationStride;
        uvec2 at = min(pixel, last);   // a load in the image for every lane; samples past the tile's last are ignored
        float d = depthAt(at.y * size.x + at.x);
        if (all(lessThanEqual(pixel, last)) && d >= frame.minDepth && d <= frame.maxDepth) {
            ++n;
            precise vec3 p = vec3(rayOf(pixel) * d, d) - origin0;
            s1 += p;
            sxx += p.x * p.x; sxy += p.x * p.y; syy += p.y * p.y; sxz += p.x * p.z; syz += p.y * p.z;
        }
    }
    // The first rules (a map's frames allocated with them: shared_layout.h, ALLOC_TILE_RULES_FIRST) left tiles
    // without depth and planes with g < 0 to the pixels.
    bool firstRules = params.allocationTiles == ALLOC_TILE_RULES_FIRST;
    if (n == 0u && !firstRules) return true;   // nothing for the pixels to walk either: the tile's rows are skipped
    if (n < ALLOC_TILE_MIN_VALID) return false;
    precise vec3 mean = s1 / float(n);
    sxx -= s1.x * mean.x; sxy -= s1.x * mean.y; syy -= s1.y * mean.y; sxz -= s1.x * mean.z; syz -= s1.y * mean.z;
    precise float det = sxx * syy - sxy * sxy;
    precise float detBound = 1e-6 * sxx * syy;
    if (!(det > detBound) || !(sxx > 0.0) || !(syy > 0.0)) return false;
    precise float a = (sxz * syy - syz * sxy) / det;
    precise float b = (syz * sxx - sxz * sxy) / det;
    mean += origin0;
    precise float g = mean.z - a * mean.x - b * mean.y;
    // The plane lies in front of the camera on a ray where g / D > 0, so D must take g's sign on every ray of the
    // tile. With g < 0 (a plane whose extension crosses the optical axis behind the camera: a wall seen obliquely)
    // the argument above holds with |D| in place of D.
    bool positive = g > 0.0 || firstRules;
    // The largest residual along the rays.
    precise float r = 0.0;
    for (uint j = 0u; j < ALLOC_TILE * ALLOC_TILE; ++j) {
        uvec2 pixel = first + uvec2(j % ALLOC_TILE, j / ALLOC_TILE) * params.allocationStride;
        uvec2 at = min(pixel, last);
        float d = depthAt(at.y * size.x + at.x);
        if (all(lessThanEqual(pixel, last)) && d >= frame.minDepth && d <= frame.maxDepth) {
            vec2 ray = rayOf(pixel);
            precise float D = 1.0 - a * ray.x - b * ray.y;
            precise float residual = abs(d - g / D);
            r = max(r, (positive ? D : -D) > 0.0 ? residual : 1e30);
        }
    }
    if (!(r <= ALLOC_TILE_MAX_RESIDUAL * params.truncation)) return false;
    // The tile's rays lie in the box of its first and last samples' rays (ordered: a focal length may be negative,
    // as ICL-NUIM's fy); D at the box's corner rays (00, 10, 11, 01), its largest value bounding it on the tile.
    vec2 rayFirst = rayOf(first), rayLast = rayOf(last);
    vec2 r00 = min(rayFirst, rayLast), r11 = max(rayFirst, rayLast), r10 = vec2(r11.x, r00.y), r01 = vec2(r00.x, r11.y);
    precise vec4 D = vec4(1.0) - a * vec4(r00.x, r10.x, r11.x, r01.x) - b * vec4(r00.y, r10.y, r11.y, r01.y);
    vec4 sD = positive ? D : -D;
    if (!all(greaterThan(sD, vec4(0.0)))) return false;
    precise float m = (params.truncation + r) * max(max(sD.x, sD.y), max(sD.z, sD.w)) * 1.0001 + 1e-5;
    // The slab's planes z - a x - b y = g -+ m; along the rays the first lies nearer the camera where g > 0, the
    // second where g < 0, and that one must still meet the rays in front of it.
    precise float lowOffset = g - m, highOffset = g + m;
    if (!((positive ? lowOffset : -highOffset) > 0.0)) return false;
    // The slab's 8 corners in world block units: their box bounds the blocks to test.
    float blockSize = params.voxelSize * float(BLOCK_SIDE);
    precise vec3 origin = transformPoint(framePose.cameraToWorld, vec3(0.0));
    precise vec3 lo = vec3(1e30), hi = vec3(-1e30);
    [[unroll]] for (uint k = 0u; k < 4u; ++k) {
        vec2 ray = k == 0u ? r00 : k == 1u ? r10 : k == 2u ? r11 : r01;
        float Dk = k == 0u ? D.x : k == 1u ? D.y : k == 2u ? D.z : D.w;
        precise float lowZ = lowOffset / Dk, highZ = highOffset / Dk;
        precise vec3 lowP = transformPoint(framePose.cameraToWorld, vec3(ray, 1.0) * lowZ) / blockSize;
        precise vec3 highP = transformPoint(framePose.cameraToWorld, vec3(ray, 1.0) * highZ) / blockSize;
        lo = min(lo, min(lowP, highP));
        hi = max(hi, max(lowP, highP));
    }
    ivec3 c0 = ivec3(floor(lo - ALLOC_SLAB_MARGIN)), c1 = ivec3(floor(hi + ALLOC_SLAB_MARGIN));
    ivec3 extent = c1 - c0 + 1;
    uint cells = uint(extent.x * extent.y * extent.z);
    if (cells > ALLOC_TILE_MAX_BLOCKS) return false;
    // The six planes, inside = positive side: the slab's two (normal -+(-a, -b, 1) in the camera frame) and the
    // pyramid's four sides (through the camera centre, normals towards the tile's rays).
    vec3 slabN = vec3(-a, -b, 1.0);
    vec4 lowPlane = planeToBlocks(slabN, lowOffset, origin, blockSize);
    vec4 highPlane = planeToBlocks(-slabN, -highOffset, origin, blockSize);
    vec4 side0 = planeToBlocks(sideNormal(r00, r10), 0.0, origin, blockSize);   // y / z >= r00.y
    vec4 side1 = planeToBlocks(sideNormal(r10, r11), 0.0, origin, blockSize);   // x / z <= r11.x
    vec4 side2 = planeToBlocks(sideNormal(r11, r01), 0.0, origin, blockSize);   // y / z <= r11.y
    vec4 side3 = planeToBlocks(sideNormal(r01, r00), 0.0, origin, blockSize);   // x / z >= r00.x
    valid += n;
    uint ex = uint(extent.x), ey = uint(extent.y);
    for (uint i = 0u; i < cells; ++i) {
        ivec3 cell = c0 + ivec3(i % ex, (i / ex) % ey, i / (ex * ey));
        vec3 c = vec3(cell);
        if (boxOutside(c, lowPlane.xyz, lowPlane.w) || boxOutside(c, highPlane.xyz, highPlane.w) ||
            boxOutside(c, side0.xyz, side0.w) || boxOutside(c, side1.xyz, side1.w) ||
            boxOutside(c, side2.xyz, side2.w) || boxOutside(c, side3.xyz, side3.w)) continue;
        visitBlock(cell);
    }
    return true;
}

void main() {
    uvec2 size = frameImageSize();
    uvec2 samples = (size + params.allocationStride - 1u) / params.allocationStride;
    uvec2 tiles = (samples + ALLOC_TILE - 1u) / ALLOC_TILE;
    uvec2 tile = gl_GlobalInvocationID.xy;
    uint valid = 0u;
    if (all(lessThan(tile, tiles))) {
        bool covered = false;
        if (!frameSkipped()) {
            uvec2 first = tile * ALLOC_TILE * params.allocationStride;
            uvec2 last = min(first + (ALLOC_TILE - 1u) * params.allocationStride, (samples - 1u) * params.allocationStride);
            covered = walkSlab(first, last, size, valid);
        }
        tileCovered[tile.y * tiles.x + tile.x] = covered ? 1u : 0u;
    }
    ADD_COUNTER(validPixels, valid);
    ADD_COUNTER(blockRequests, requests);
    ADD_COUNTER(blocksFound, found);
    ADD_COUNTER(blocksInserted, inserted);
    ADD_COUNTER(hashFull, full);
    ADD_COUNTER(outOfRange, outOfRange);
    ADD_COUNTER(outsideRadius, outsideRadius);
    ADD_COUNTER(blocksShared, repeated);
}
