// The frame's depth image in metres (0 = no measurement), row-major, uploaded each frame.
#ifndef VKMESH_DEPTH_INPUT_GLSL
#define VKMESH_DEPTH_INPUT_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_DEPTH) readonly buffer Depth { float depth[]; };
#endif
