#version 460
// One invocation after recycle_free: the pushed blocks join the free list; their keys became tombstones.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.freeTop += counters.blocksFreed;
    counters.blocksInUse -= counters.blocksFreed;
    counters.hashEntries -= counters.blocksFreed;
    counters.hashTombstones += counters.blocksFreed;
}
