#version 460
// One invocation after assign_blocks: pops the blocks handed out from the free list and records how
// many requests the pool could not serve; then defers the frame if its allocation overflowed (frame/defer_frame.glsl).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "frame/defer_frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint granted = min(counters.allocRequests, counters.freeTop);
    counters.poolExhausted = counters.allocRequests - granted;
    counters.freeTop -= granted;
    counters.blocksInUse += granted;
    counters.hashEntries += counters.blocksInserted;
    deferFrameOnOverflow();
}
