#version 450
// Tracking, one ICP iteration at one level, part 1 (track/icp_reduce.glsl): the per-pixel maps read as texel
// buffers, the default wherever the pyramid fits the device's maxTexelBufferElements.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define TRACK_READ_TEXELS
#include "track/icp_reduce.glsl"
