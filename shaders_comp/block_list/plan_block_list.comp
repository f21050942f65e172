#version 460
// One invocation after collect_blocks: one workgroup per listed block for the whole-volume pass.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    // A deferred frame (frame/defer_frame.glsl) runs no whole-volume pass: recycling must not decay or free twice.
    counters.listDispatch[0] = counters.frameDeferred != 0u ? 0u : counters.liveBlockCount;
    counters.listDispatch[1] = 1u;
    counters.listDispatch[2] = 1u;
}
