#version 450
// Tracking, one ICP iteration at one level, part 1 (track/icp_reduce.glsl): the per-pixel maps read as storage
// buffers, for a device whose maxTexelBufferElements is below the pyramid's pixel count (the Vulkan minimum is
// 65,536; a 640 x 480 pyramid has 409,600), or when TrackerOptions::texelReads is off.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "track/icp_reduce.glsl"
