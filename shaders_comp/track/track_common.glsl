// What the tracker's passes see (shared_layout.h, "camera tracking"): their settings, the push constants of
// the level being processed, and the pyramids of per-pixel maps. Same rules as structure/frame.glsl: no
// invocation waits for another, every loop has a small static bound, and sums are formed in a fixed order so
// that the same frames give the same poses bit for bit (no float atomics).
#ifndef VKMESH_TRACK_COMMON_GLSL
#define VKMESH_TRACK_COMMON_GLSL
#ifndef VKMESH_HASH32
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require   // shared_layout.h declares 64-bit constants
#endif
#extension GL_EXT_control_flow_attributes : require   // [[unroll]] (structure/frame.glsl)

#include "shared_layout.h"
#include "structure/rigid.glsl"

layout(std140, set = 0, binding = TRACK_BINDING_PARAMS) uniform TrackParamsBuffer { TrackParamsGpu track; };
layout(std430, set = 0, binding = TRACK_BINDING_RAW_DEPTH) readonly buffer RawDepth { float rawDepth[]; };
layout(std430, set = 0, binding = TRACK_BINDING_DEPTH) buffer DepthPyramid { float depthPyramid[]; };
layout(std430, set = 0, binding = TRACK_BINDING_VERTICES) buffer VertexPyramid { vec4 vertexPyramid[]; };
layout(std430, set = 0, binding = TRACK_BINDING_NORMALS) buffer NormalPyramid { vec4 normalPyramid[]; };
layout(std430, set = 0, binding = TRACK_BINDING_MODEL_POSITIONS) buffer ModelPositions { vec4 modelPositions[]; };
layout(std430, set = 0, binding = TRACK_BINDING_MODEL_NORMALS) buffer ModelNormals { vec4 modelNormals[]; };
layout(std430, set = 0, binding = TRACK_BINDING_PARTIALS) buffer Partials { float partials[]; };
layout(std430, set = 0, binding = TRACK_BINDING_SUMS) buffer Sums { float sums[]; };
layout(std430, set = 0, binding = TRACK_BINDING_INTENSITY) buffer IntensityPyramid { float intensityPyramid[]; };
layout(std430, set = 0, binding = TRACK_BINDING_MODEL_INTENSITY) buffer ModelIntensity { float modelIntensity[]; };

layout(std430, set = 0, binding = TRACK_BINDING_STATE) buffer State { TrackStateGpu state; };

layout(push_constant) uniform Push { TrackPush pass; };

uvec2 levelSize() { return uvec2(pass.size & 0xFFFFu, pass.size >> 16); }

// The GPU-solved mode (TRACK_FLAG_STATE): the level this ICP pass belongs to, and whether that level has
// stopped (a tiny or unsolvable step), so that its remaining iterations do nothing. The same value for every
// invocation of a dispatch (it is read from memory the previous dispatch wrote).
bool solvedOnGpu() { return (pass.flags & TRACK_FLAG_STATE) != 0u; }
uint passLevel() { return pass.flags >> TRACK_FLAG_LEVEL_SHIFT; }
bool levelStopped() { return solvedOnGpu() && state.stoppedLevel == passLevel() + 1u; }

// A depth sample is a measurement when it lies in [minDepth, maxDepth] (maxDepth 0: no upper limit); NaN and
// infinities never are.
bool measured(float d) { return d >= track.minDepth && d > 0.0 && (track.maxDepth <= 0.0 || d <= track.maxDepth) && !isinf(d); }
#endif
