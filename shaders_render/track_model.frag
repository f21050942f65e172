#version 450
// Model maps for tracking, fragment stage: the nearest surface's world position and unit normal, w = 1; the
// maps are cleared to 0, so w = 0 means "no model at this pixel".
layout(location = 0) in vec3 worldPos;
layout(location = 1) in vec3 worldNormal;

layout(location = 0) out vec4 outPosition;
layout(location = 1) out vec4 outNormal;

void main() {
    float length2 = dot(worldNormal, worldNormal);
    if (!(length2 > 0.0)) discard;   // a vertex without a normal: not a usable model point
    outPosition = vec4(worldPos, 1.0);
    outNormal = vec4(worldNormal * inversesqrt(length2), 1.0);
}
