#version 450
// Three vertex attributes, the last a uint (VK_FORMAT_R32_UINT), all passed on as varyings.
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in uint inCreated;
layout(location = 0) out vec3 position;
layout(location = 1) out vec3 normal;
layout(location = 2) out float created;
void main() {
    position = inPosition;
    normal = inNormal;
    created = float(inCreated);
    gl_Position = vec4(inPosition, 1.0);
}
