#version 460
// Stage 3 (paper §V.A): one workgroup per touched block updates the TSDF at the block's 512 corners:
// project the corner into the depth image (nearest pixel), take the projective distance
// d(pixel) - z, truncate it, and fold it into the weighted running average (weight capped). With colour,
// the pixel's colour is folded into the corner's in the same step with the same weight (voxel_color.glsl).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"
#include "structure/retype_marks.glsl"
#include "structure/depth_input.glsl"
#include "structure/voxel_color.glsl"

layout(local_size_x = WG_BLOCK) in;

// Corners whose sign or observed state flips mark the cubes around them (markCornerRetype, structure/retype_marks.glsl).

void main() {
    uint entry = touched[gl_WorkGroupID.x];   // the same for the whole workgroup
    uint updated = 0u;
    uint fused = 0u;
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
        for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
            uint local = gl_LocalInvocationIndex + k * WG_BLOCK;
            uvec3 l = uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
            uint v = block * VOXELS_PER_BLOCK + local;
            // A block handed out this frame may hold a previous owner's values: start from nothing.
            float oldSdf = fresh ? 0.0 : voxelSdf[v];
            float oldWeight = fresh ? 0.0 : voxelWeight[v];
            precise float newSdf = oldSdf;
            float newWeight = oldWeight;

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
                        precise float tsdf = min(sdf, trunc);
                        newSdf = (oldSdf * oldWeight + tsdf) / (oldWeight + 1.0);
                        newWeight = min(oldWeight + 1.0, params.maxWeight);
                        ++updated;
                        uint rgba = withColor ? colorAt(pixel, size.x * size.y) : 0u;
                        if ((rgba >> 24) != 0u) {
                            uint oldColor = fresh ? 0u : voxelColor[v];
                            uvec3 rgb = uvec3(rgba, rgba >> 8, rgba >> 16) & 0xFFu;
                            voxelColor[v] = foldVoxelColor(oldColor, oldWeight, newSdf, rgb, origin + ivec3(l));
                        } else if (fresh && volumeKeepsColor()) {
                            voxelColor[v] = 0u;
                        }
                    }
                }
            }
            bool wasObserved = oldWeight >= params.minMeshWeight, isObserved = newWeight >= params.minMeshWeight;
            if (wasObserved != isObserved || (isObserved && (oldSdf < 0.0) != (newSdf < 0.0))) flipped |= 1u << k;
            // With refinement the masks of the TSDF that decide_mesh_signs reads (a fresh block's are zero, as are
            // the old values it starts from).
            if (volumeRefines()) maskChange |= (tsdfMaskBits(oldSdf, oldWeight) ^ tsdfMaskBits(newSdf, newWeight)) << (3u * k);
            if (fresh || newWeight != oldWeight || newSdf != oldSdf) {
                voxelSdf[v] = newSdf;
                voxelWeight[v] = newWeight;
            }
            // A fresh block's corners that this frame did not update still hold a previous owner's colour.
            if (fresh && newWeight == 0.0 && volumeKeepsColor()) voxelColor[v] = 0u;
        }
        if (params.incrementalMesh != 0u) {
            for (uint k = 0u; k < VOXELS_PER_INVOCATION && flipped != 0u; ++k) {
                if ((flipped & (1u << k)) != 0u) markCornerRetype(block, gl_LocalInvocationIndex + k * WG_BLOCK);
            }
        }
        // Uniform over the subgroup (most subgroups' corners change no mask bit: skipped with one subgroup op).
        if (volumeRefines() && subgroupOr(maskChange) != 0u) toggleTsdfMasks(block, maskChange);
    }
    ADD_COUNTER(updatedVoxels, updated);
    ADD_COUNTER(fusedBlocks, fused);
}
