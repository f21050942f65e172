#version 460
// One invocation after rehash_insert: the table now holds exactly the live blocks, no tombstones (keys that
// held no block, left by an exhausted pool, are dropped: they ask again when next touched).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.hashEntries = counters.liveBlockCount - counters.rehashLost;
    counters.hashTombstones = 0u;
    counters.hashRebuilt = 1u;
}
