#version 460
// Recycling, phase 1 (after fusion and mark_dirty, before the mesh passes): one workgroup per live block
// (collect_blocks). A block beyond the keep radius has every weight set to 0; a block idle for
// starveAfterFrames frames loses starveWeight per corner (not below 0; its distance stays: starvedSum). A corner that stops being
// observed (weight drops below minMeshWeight) marks the cubes around it for retyping, exactly as fusion
// does, and the block and its -x/-y/-z neighbours (whose cubes read its corners; with refinement all 26) become dirty: the mesh
// passes of this same frame then release every triangle that read those corners, and GC frees their
// vertices. recycle_free frees the block once it owns no TSDF weight, triangle or vertex.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"
#include "structure/retype_marks.glsl"
#include "recycle/recycle.glsl"

layout(local_size_x = WG_BLOCK) in;

void main() {
    uint block = blockList[gl_WorkGroupID.x];   // the same for the whole workgroup
    bool retire = blockRetires(block);
    bool starve = !retire && blockStarves(block);
    if (!retire && !starve) return;             // uniform over the workgroup
    uint flipped = 0u;
    uint maskChange = 0u;   // with refinement: bits 3k..3k+2, how corner k's TSDF masks change (tsdfMaskBits)
    [[unroll]] for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        uint v = block * VOXELS_PER_BLOCK + cornerOfInvocation(k);   // (the corners' nibbles: toggleTsdfMasks)
        float oldWeight = voxelWeight[v];
        precise float newWeight = retire ? 0.0 : max(oldWeight - params.starveWeight, 0.0);
        if (newWeight == oldWeight) continue;
        int oldSum = voxelSdfSum[v];
        int newSum = starvedSum(oldSum, oldWeight, newWeight);   // the distance stays (its sign too)
        voxelWeight[v] = newWeight;
        voxelSdfSum[v] = newSum;
        if ((oldWeight >= params.minMeshWeight) != (newWeight >= params.minMeshWeight)) flipped |= 1u << k;
        if (volumeRefines()) {
            uint before = tsdfMaskBits(tsdfMean(oldSum, oldWeight), oldWeight);
            maskChange |= (before ^ tsdfMaskBits(tsdfMean(newSum, newWeight), newWeight)) << (3u * k);
        }
    }
    if (volumeRefines() && subgroupOr(maskChange) != 0u) toggleTsdfMasks(block, maskChange);   // uniform over the subgroup
    if (params.incrementalMesh != 0u) {
        for (uint k = 0u; k < VOXELS_PER_INVOCATION && flipped != 0u; ++k)
            if ((flipped & (1u << k)) != 0u) markCornerRetype(block, cornerOfInvocation(k));
        // One invocation per subgroup that saw a flip lists the dirty blocks; the stamp lists each once.
        if (subgroupOr(flipped) != 0u && subgroupElect()) {
            // With refinement the meshing signs of corners in the blocks at +-1 read these corners, as in mark_dirty.
            ivec3 coord = blockCoords[block].xyz;
            uint n = volumeRefines() ? 27u : 8u;
            for (uint o = 0u; o < n; ++o) {
                ivec3 offset = volumeRefines() ? ivec3(int(o % 3u), int((o / 3u) % 3u), int(o / 9u)) - 1
                                                   : ivec3(o & 1u, (o >> 1) & 1u, (o >> 2) & 1u);
                uint b = offset == ivec3(0) ? block : findBlock(coord - offset);
                if (b == NO_BLOCK) continue;
                markBlockDirty(b, dirtyMarkAt(offset));
            }
        }
    }
    if (gl_LocalInvocationIndex == 0u) {
        if (retire) atomicAdd(counters.blocksRetired, 1u); else atomicAdd(counters.blocksStarved, 1u);
    }
}
