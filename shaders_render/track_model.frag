#version 450
// Model maps for tracking, fragment stage: the nearest surface's world position and unit normal, w = 1, and
// its vertex colours' intensity; the maps are cleared to w = 0 (and -1), so w = 0 means "no model at this
// pixel". Only front faces are drawn (src/gpu/tracking/model_maps.cpp, record()).
layout(location = 0) in vec3 worldPos;
layout(location = 1) in vec3 worldNormal;
layout(location = 2) in float intensity;

layout(location = 0) out vec4 outPosition;
layout(location = 1) out vec4 outNormal;
layout(location = 2) out float outIntensity;   // in [0, 1]; -1: no colour here

void main() {
    float length2 = dot(worldNormal, worldNormal);
    if (!(length2 > 0.0)) discard;   // a vertex without a normal: not a usable model point
    outPosition = vec4(worldPos, 1.0);
    outNormal = vec4(worldNormal * inversesqrt(length2), 1.0);
    outIntensity = intensity >= 0.0 ? intensity : -1.0;
}
