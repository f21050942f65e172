#version 450
// Tracking, pass 1: the frame's depth -> level 0 of the depth pyramid, through an edge-preserving bilateral
// filter (KinectFusion's: Gaussian in pixels and in depth). A pixel without a measurement stays without one;
// neighbours without one do not count. Only tracking reads the filtered depth: fusion takes the raw frame.
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(local_size_x = WG_TRACK_PIXELS_X, local_size_y = WG_TRACK_PIXELS_Y) in;

const int MAX_FILTER_RADIUS = 4;   // static loop bound; TrackerOptions caps filterRadius at it

void main() {
    uvec2 size = levelSize();
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    uint index = pixel.y * size.x + pixel.x;
    float centre = rawDepth[index];
    if (!measured(centre)) {
        depthPyramid[index] = 0.0;
        return;
    }
    int radius = min(int(track.filterRadius), MAX_FILTER_RADIUS);
    precise float spatial = -0.5 / (track.filterSpatialSigma * track.filterSpatialSigma);
    precise float range = -0.5 / (track.filterDepthSigma * track.filterDepthSigma);
    precise float sum = 0.0;
    precise float weights = 0.0;
    for (int dy = -MAX_FILTER_RADIUS; dy <= MAX_FILTER_RADIUS; ++dy) {
        for (int dx = -MAX_FILTER_RADIUS; dx <= MAX_FILTER_RADIUS; ++dx) {
            if (abs(dx) > radius || abs(dy) > radius) continue;
            ivec2 q = ivec2(pixel) + ivec2(dx, dy);
            if (q.x < 0 || q.y < 0 || q.x >= int(size.x) || q.y >= int(size.y)) continue;
            float d = rawDepth[uint(q.y) * size.x + uint(q.x)];
            if (!measured(d)) continue;
            precise float diff = d - centre;
            precise float w = exp(float(dx * dx + dy * dy) * spatial + diff * diff * range);
            sum += w * d;
            weights += w;
        }
    }
    depthPyramid[index] = sum / weights;   // weights >= 1: the centre itself
}
