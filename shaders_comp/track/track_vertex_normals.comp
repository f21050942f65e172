#version 450
// Tracking, pass 3 (per level): each depth pixel's camera-space point, and its normal from the points to the
// right and below. No normal where a neighbour is missing or lies across a depth edge (further than
// edgeJumpFraction of the depth): such a normal would join two surfaces. Normals face the camera, whatever the
// sign of fy (ICL-NUIM's is negative).
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(local_size_x = WG_TRACK_PIXELS_X, local_size_y = WG_TRACK_PIXELS_Y) in;

vec3 backProject(uvec2 pixel, float d) {
    precise vec3 p;
    p.x = (float(pixel.x) - pass.intrinsics.z) / pass.intrinsics.x * d;
    p.y = (float(pixel.y) - pass.intrinsics.w) / pass.intrinsics.y * d;
    p.z = d;
    return p;
}

void main() {
    uvec2 size = levelSize();
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    uint index = pass.offset + pixel.y * size.x + pixel.x;
    float d = depthPyramid[index];
    if (d <= 0.0) {
        vertexPyramid[index] = vec4(0.0);
        normalPyramid[index] = vec4(0.0);
        return;
    }
    vec3 p = backProject(pixel, d);
    vertexPyramid[index] = vec4(p, 1.0);
    vec4 normal = vec4(0.0);
    if (pixel.x + 1u < size.x && pixel.y + 1u < size.y) {
        float dRight = depthPyramid[index + 1u];
        float dDown = depthPyramid[index + size.x];
        float jump = track.edgeJumpFraction * d;
        if (dRight > 0.0 && dDown > 0.0 && abs(dRight - d) <= jump && abs(dDown - d) <= jump) {
            precise vec3 n = cross(backProject(pixel + uvec2(1u, 0u), dRight) - p, backProject(pixel + uvec2(0u, 1u), dDown) - p);
            precise float length2 = dot(n, n);
            if (length2 > 0.0) {
                n = n / sqrt(length2);
                if (dot(n, p) > 0.0) n = -n;   // towards the camera
                normal = vec4(n, 1.0);
            }
        }
    }
    normalPyramid[index] = normal;
}
