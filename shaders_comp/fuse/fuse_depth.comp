#version 460
// Stage 3 (paper §V.A): one workgroup per touched block updates the TSDF at the block's 512 corners:
// project the corner into the depth image (nearest pixel), take the projective distance
// d(pixel) - z, truncate it, round it to a whole number of steps and add it to the corner's sum, counting the
// observation (shared_layout.h, "A TSDF corner"). A de-integrated frame (framePose.deintegrate) subtracts the
// same steps at the same corners instead, which restores every bit. With colour, the pixel's colour is folded
// into the corner's running average in the same step with the same weight (voxel_color.glsl), or out of it.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"
#include "structure/depth_input.glsl"
#include "structure/voxel_color.glsl"

layout(local_size_x = WG_BLOCK) in;
layout(constant_id = 0) const uint FUSE_DIRECTION = FUSE_BY_FRAME;   // shared_layout.h

// Corners whose sign or observed state flips are recorded (recordCornerFlips, structure/frame_lists.glsl) for
// decide_mesh_signs to mark the cubes around them.

void main() {
    uint entry = touched[gl_WorkGroupID.x];   // the same for the whole workgroup
    uint updated = 0u, dropped = 0u;
    uint fused = 0u;
    // De-integration: allocation listed only blocks already in the map (a fresh one, a key that had no block,
    // holds nothing to take out: its corners count as dropped and it is cleared like any fresh block).
    bool removing = FUSE_DIRECTION == FUSE_BY_FRAME ? framePose.deintegrate != 0u : FUSE_DIRECTION == FUSE_DEINTEGRATE;
    if (entry != NO_BLOCK) {
        fused = gl_LocalInvocationIndex == 0u ? 1u : 0u;
        bool fresh = (entry & FRESH_BLOCK) != 0u;
        uint block = entry & INDEX_MASK;
        ivec3 origin = blockCoords[block].xyz * int(BLOCK_SIDE);
        uvec2 size = frameImageSize();
        float trunc = params.truncation;
        bool withColor = volumeKeepsColor() && frameHasColor();
        vec4 worldToCamera[3] = framePose.worldToCamera;   // read once, not per corner
        uint flipped = 0u;   // which of this invocation's corners flipped (marked after the loop, which stays lean)
        uint maskChange = 0u;    // with refinement: bits 3k..3k+2, how corner k's TSDF masks change (tsdfMaskBits)
        // The invocation's 4 corners (x to x + 3 of a row), read with one load per array and written with one store
        // (cornerOfInvocation, block_store.glsl). A block handed out this frame may hold a previous owner's values:
        // start from nothing.
        uint quad = cornerQuadOfInvocation(block);
        ivec4 oldSums = fresh ? ivec4(0) : voxelSdfSum4[quad];
        vec4 oldWeights = fresh ? vec4(0.0) : voxelWeight4[quad];
        uvec4 oldColors = volumeKeepsColor() && !fresh ? voxelColor4[quad] : uvec4(0u);
        ivec4 newSums = oldSums;
        vec4 newWeights = oldWeights;
        uvec4 newColors = oldColors;
        bool colorsChanged = false;
        [[unroll]] for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
            uint local = cornerOfInvocation(k);
            uvec3 l = uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
            int oldSum = oldSums[k];
            float oldWeight = oldWeights[k];
            int newSum = oldSum;
            float newWeight = oldWeight;
            // The distances before and after, computed only for a corner this frame changes (the others keep
            // theirs, flip nothing and change no mask): a division each, which the lean loop should not pay for all.
            float oldSdf = 0.0, newSdf = 0.0;
            bool changed = false;
            // The corner's colour word when this frame changes it; every colour store is the one after the loop
            // (llvmpipe turns each store site under divergent control flow into a per-lane scatter of its own).
            uint newColor = 0u;
            bool colorChanged = false;

            precise vec3 world = vec3(origin + ivec3(l)) * params.voxelSize;
            precise vec3 cam = transformPoint(worldToCamera, world);
            if (cam.z > 0.0) {
                precise float u = (cam.x * frame.intrinsics.x) / cam.z + frame.intrinsics.z;
                precise float w = (cam.y * frame.intrinsics.y) / cam.z + frame.intrinsics.w;
                float pu = floor(u + 0.5), pv = floor(w + 0.5);
                if (pu >= 0.0 && pv >= 0.0 && pu < float(size.x) && pv < float(size.y)) {
                    uint pixel = uint(pv) * size.x + uint(pu);
                    float d = depthAt(pixel);
                    precise float sdf = d - cam.z;
                    if (d >= frame.minDepth && d <= frame.maxDepth && sdf >= -trunc) {
                        int steps = tsdfSteps(min(sdf, trunc));
                        // Past the count that keeps the sum in range, or nothing left to take out: counted, not applied.
                        bool applies = removing ? oldWeight >= 1.0 : oldWeight < float(SDF_MAX_COUNT);
                        if (applies) {
                            newSum = removing ? oldSum - steps : oldSum + steps;
                            newWeight = removing ? oldWeight - 1.0 : oldWeight + 1.0;
                            if (newWeight == 0.0) newSum = 0;   // (already 0 when the map holds the frame)
                            oldSdf = tsdfMean(oldSum, oldWeight);
                            newSdf = tsdfMean(newSum, newWeight);
                            changed = true;
                            ++updated;
                        } else {
                            ++dropped;
                        }
                        uint rgba = withColor ? colorAt(pixel, size.x * size.y) : 0u;
                        if (applies && (rgba >> 24) != 0u) {
                            uint oldColor = oldColors[k];   // (0 in a fresh block)
                            uvec3 rgb = uvec3(rgba, rgba >> 8, rgba >> 16) & 0xFFu;
                            newColor = !removing ? foldVoxelColor(oldColor, oldWeight, newSdf, rgb, origin + ivec3(l))
                                     : newWeight == 0.0 ? 0u : unfoldVoxelColor(oldColor, oldWeight, newSdf, rgb, origin + ivec3(l));
                            colorChanged = true;
                        } else if (applies && removing && newWeight == 0.0) {
                            colorChanged = true;   // no observation left: no colour either (newColor 0)
                        }
                    }
                }
            }
            bool wasObserved = oldWeight >= params.minMeshWeight, isObserved = newWeight >= params.minMeshWeight;
            // With refinement a cube's type follows its corners' meshing signs, which decide_mesh_signs re-decides
            // from the masks below and marks where they change: a raw sign flip (mostly noise that refinement
            // absorbs) marks nothing here, only a change of the observed state does.
            bool signFlipped = isObserved && (oldSdf < 0.0) != (newSdf < 0.0) && !volumeRefines();
            if (changed && (wasObserved != isObserved || signFlipped)) flipped |= 1u << k;
            // With refinement the masks of the TSDF that decide_mesh_signs reads (a fresh block's are zero, as are
            // the old values it starts from).
            if (volumeRefines() && changed) maskChange |= (tsdfMaskBits(oldSdf, oldWeight) ^ tsdfMaskBits(newSdf, newWeight)) << (3u * k);
            newSums[k] = newSum;
            newWeights[k] = newWeight;
            if (colorChanged) newColors[k] = newColor;
            colorsChanged = colorsChanged || colorChanged;
        }
        if (fresh || newSums != oldSums || newWeights != oldWeights) {
            voxelSdfSum4[quad] = newSums;
            voxelWeight4[quad] = newWeights;
        }
        // A fresh block's corners that this frame gave no colour still hold a previous owner's: cleared (0).
        if (volumeKeepsColor() && (colorsChanged || fresh)) voxelColor4[quad] = newColors;
        // Uniform over the subgroup (most subgroups flip no corner: skipped with one subgroup op).
        if (params.incrementalMesh != 0u && subgroupOr(flipped) != 0u) recordCornerFlips(block, flipped);
        // Uniform over the subgroup (most subgroups' corners change no mask bit: skipped with one subgroup op).
        if (volumeRefines() && subgroupOr(maskChange) != 0u) toggleTsdfMasks(block, maskChange);
    }
    ADD_COUNTER(updatedVoxels, updated);
    // Rare or once per block: an atomic where they occur rather than a subgroup sum in every subgroup.
    if (dropped != 0u) atomicAdd(counters.observationsDropped, dropped);
    if (fused != 0u) atomicAdd(counters.fusedBlocks, fused);
}
