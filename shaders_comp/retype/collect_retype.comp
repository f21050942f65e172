#version 460
// Incremental mesh: turns the dirty blocks' retype masks (set by fuse_depth, decide_mesh_signs, and by
// mesh_triangulate for INCOMPLETE cubes) into one list of cubes, and clears the bits it listed. One invocation
// per mask word; bits that do not fit in the list stay set for the next pass (counted). Room in the list is reserved
// with one atomic per subgroup, which also raises mesh_claim's dispatch (Counters::retypeDispatch, from 0 at the
// frame's start: CounterBuffer::recordClearFrame) to cover it: a pass of one invocation to size it cost a dispatch
// and a barrier.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.dirtyCount * MASK_WORDS) return;
    uint block = dirtyList[i / MASK_WORDS];
    uint word = block * MASK_WORDS + i % MASK_WORDS;
    uint bits = retypeMask[word];
    uint n = bitCount(bits);
    uint offset = subgroupExclusiveAdd(n);
    uint total = subgroupAdd(n);
    uint base = 0u;
    if (subgroupElect() && total != 0u) {
        base = atomicAdd(counters.retypeCount, total);
        atomicMax(counters.retypeDispatch[0], (min(base + total, params.retypeCapacity) + WG_LIST - 1u) / WG_LIST);
    }
    uint at = subgroupBroadcastFirst(base) + offset;
    if (n == 0u) return;
    if (at + n > params.retypeCapacity) {
        atomicAdd(counters.retypeDeferred, n);
        // Entries of the list this word would have used stay unused: mark them so nobody reads garbage.
        for (uint k = at; k < params.retypeCapacity && k < at + n; ++k) retypeList[k] = NO_BLOCK;
        return;
    }
    retypeMask[word] = 0u;
    uint first = block * VOXELS_PER_BLOCK + (i % MASK_WORDS) * 32u;
    for (uint k = 0u; k < n; ++k) {   // over the set bits (at most 32)
        uint b = findLSB(bits);
        bits &= bits - 1u;
        retypeList[at + k] = first + b;
    }
}
