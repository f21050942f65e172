#version 450
// Tracking, model maps (once per coarser level): level l+1 of the model's position and normal maps from
// level l. Like the depth pyramid: the 2 x 2 fine pixels with a model that lie within modelMergeDistance of the
// first one are averaged (normals renormalised), so that no coarse pixel joins two surfaces.
#extension GL_GOOGLE_include_directive : require
#include "track/track_common.glsl"

layout(local_size_x = WG_TRACK_PIXELS_X, local_size_y = WG_TRACK_PIXELS_Y) in;

void main() {
    uvec2 size = levelSize();
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    vec4 reference = vec4(0.0);
    [[unroll]] for (uint k = 0u; k < 4u; ++k) {
        uvec2 q = pixel * 2u + uvec2(k & 1u, k >> 1u);
        vec4 p = modelPositions[pass.finerOffset + q.y * pass.finerWidth + q.x];
        if (reference.w == 0.0 && p.w != 0.0) reference = p;
    }
    precise vec3 position = vec3(0.0);
    precise vec3 normal = vec3(0.0);
    precise float intensity = 0.0;
    float count = 0.0, coloured = 0.0;
    [[unroll]] for (uint k = 0u; k < 4u; ++k) {
        uvec2 q = pixel * 2u + uvec2(k & 1u, k >> 1u);
        uint fine = pass.finerOffset + q.y * pass.finerWidth + q.x;
        vec4 p = modelPositions[fine];
        if (p.w == 0.0 || distance(p.xyz, reference.xyz) > track.modelMergeDistance) continue;
        position += p.xyz;
        normal += modelNormals[fine].xyz;
        count += 1.0;
        float i = modelIntensity[fine];
        if (i >= 0.0) intensity += i, coloured += 1.0;
    }
    uint index = pass.offset + pixel.y * size.x + pixel.x;
    float length2 = dot(normal, normal);
    modelIntensity[index] = coloured > 0.0 && length2 > 0.0 ? intensity / coloured : -1.0;
    if (count == 0.0 || length2 <= 0.0) {
        modelPositions[index] = vec4(0.0);
        modelNormals[index] = vec4(0.0);
        return;
    }
    modelPositions[index] = vec4(position / count, 1.0);
    modelNormals[index] = vec4(normal / sqrt(length2), 1.0);
}
