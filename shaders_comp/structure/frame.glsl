// What every vkmesh compute stage sees: the volume's constant parameters, the frame's push constants, the
// counters (which are also the indirect-dispatch arguments) and small grid helpers. The data structure's
// buffers are declared by one header per component, next to this one (block_hash.glsl, block_store.glsl,
// cube_mesh.glsl, frame_lists.glsl, mc_tables.glsl, depth_input.glsl); a shader includes the ones it uses,
// and its pipeline layout holds only the bindings it statically uses (src/vk/pipeline.cpp reflects them).
// Rules that hold in every stage (see ../shared/docs/lavapipe.md):
//   - no invocation waits for another; every loop has a static bound far below 65,535 iterations;
//   - what one invocation publishes with an atomic, others read in the NEXT dispatch;
//   - float expressions that the CPU reference must reproduce bit for bit are `precise`;
//   - no local array or vector is indexed by a value known only at run time (select instead: blockHolding,
//     cornerValue), and short fixed loops carry [[unroll]]: llvmpipe unrolls nothing itself, and a rolled loop
//     over a cube's 8 corners or a block's 4 corners per invocation indexes its arrays at run time, which costs
//     per-lane scratch memory or branch ladders (docs/RESULTS.md, issue 33: fusion -11 %, meshing -15 %).
#ifndef VKMESH_FRAME_GLSL
#define VKMESH_FRAME_GLSL
// The 32-bit hash variant (VKMESH_HASH32, docs/HASH.md) uses no 64-bit type at all: it runs on devices
// without shaderInt64 / shaderBufferInt64Atomics.
#ifndef VKMESH_HASH32
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_control_flow_attributes : require   // [[unroll]] (the rules above)

#include "shared_layout.h"
#include "structure/rigid.glsl"

layout(std140, set = 0, binding = BINDING_PARAMS) uniform ParamsBuffer { VolumeParamsGpu params; };
layout(std430, set = 0, binding = BINDING_COUNTERS) coherent buffer CountersBuffer { Counters counters; };

layout(push_constant) uniform Push { FramePush frame; };
// The frame's camera pose (shared_layout.h, FramePoseGpu): the host's, or the one camera tracking computed
// earlier in the same submission, which may also have decided not to fuse the frame (frameSkipped).
layout(std430, set = 0, binding = BINDING_FRAME_POSE) readonly buffer FramePoseBuffer { FramePoseGpu framePose; };

// A frame tracking lost in its own submission: nothing is allocated, fused, recycled or re-meshed, so the map
// stays bit-identical (the passes that start from the frame's depth or from the live-block list check it).
bool frameSkipped() { return framePose.skip != 0u; }

// The optional code this pipeline is built with (VOLUME_FEATURE_*, shared_layout.h): a specialisation
// constant, so what a volume does not use is compiled out. The uniform still decides within it.
layout(constant_id = 1) const uint VOLUME_FEATURES = VOLUME_FEATURES_ALL;
bool volumeKeepsColor() { return (VOLUME_FEATURES & VOLUME_FEATURE_COLOR) != 0u && params.colorMode != COLOR_MODE_OFF; }
bool volumeRefines() { return (VOLUME_FEATURES & VOLUME_FEATURE_REFINE) != 0u && params.refine != 0u; }

uvec2 frameImageSize() { return uvec2(frame.imageSize & 0xFFFFu, (frame.imageSize >> 16) & FRAME_HEIGHT_MASK); }

// Whether a block lies beyond the keep radius around the camera (its centre farther than keepRadius):
// such blocks are neither allocated nor kept. The CPU reference (src/cpu/reference_volume.cpp) repeats
// these float operations in this order.
bool blockOutsideKeepRadius(ivec3 c) {
    if (params.keepRadius <= 0.0) return false;
    float blockSize = params.voxelSize * float(BLOCK_SIDE);
    precise vec3 centre = (vec3(c) + 0.5) * blockSize;
    precise vec3 d = centre - vec3(framePose.cameraToWorld[0].w, framePose.cameraToWorld[1].w, framePose.cameraToWorld[2].w);
    precise float distance2 = d.x * d.x + d.y * d.y + d.z * d.z;
    return distance2 > params.keepRadius * params.keepRadius;
}

// Aggregates a per-invocation count over the subgroup and adds it with one atomic. Must be called in
// uniform control flow (every invocation of the workgroup reaches it).
#define ADD_COUNTER(field, value)                                   \
    {                                                               \
        uint subgroupTotal_ = subgroupAdd(value);                   \
        if (subgroupElect() && subgroupTotal_ != 0u)                \
            atomicAdd(counters.field, subgroupTotal_);              \
    }

// Reserves `count` consecutive ranks of the counter for each invocation, one atomic per subgroup (a contended
// atomic costs ~20 ns on lavapipe; per item they were ~0.1 ms of a frame's claim): `first` receives the
// invocation's first rank. Over the invocations active where it is called (all of them reach it with 0 or more).
#define RESERVE_COUNTER(field, count, first)                                       \
    {                                                                              \
        uint offset_ = subgroupExclusiveAdd(count), total_ = subgroupAdd(count);   \
        uint base_ = 0u;                                                           \
        if (subgroupElect() && total_ != 0u) base_ = atomicAdd(counters.field, total_); \
        first = subgroupBroadcastFirst(base_) + offset_;                           \
    }
#endif
