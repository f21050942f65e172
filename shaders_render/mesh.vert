#version 450
// Mesh renderer, vertex stage: world-space position and normal passed through, the vertex's age
// (frames since it was created) normalised for the colormap, and its colour.
#extension GL_GOOGLE_include_directive : require
#include "mesh_render.h"

layout(location = RENDER_LOC_POSITION) in vec3 inPosition;
layout(location = RENDER_LOC_NORMAL) in vec3 inNormal;
layout(location = RENDER_LOC_CREATED) in uint inCreated;
layout(location = RENDER_LOC_COLOR) in vec4 inColor;   // R8G8B8A8_UNORM: alpha 0 = no colour

layout(location = 0) out vec3 worldPos;
layout(location = 1) out vec3 worldNormal;
layout(location = 2) out float age;
layout(location = 3) out vec4 vertexColor;

void main() {
    worldPos = inPosition;
    worldNormal = inNormal;
    vertexColor = inColor;
    age = inCreated <= pc.newestFrame ? float(pc.newestFrame - inCreated) * pc.ageScale : 0.0;
    gl_Position = pc.viewProj * vec4(inPosition, 1.0);
}
