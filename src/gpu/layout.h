// The C++ side of shaders_comp/shared_layout.h, with the checks that keep it equal to GLSL's std430.
#pragma once

#include <cstddef>

#include "core/types.h"
#include "shared_layout.h"

namespace vkmesh::gpu {

static_assert(sizeof(VolumeParamsGpu) == 112, "VolumeParamsGpu: std140 layout of 28 scalars");
static_assert(sizeof(Counters) % 16 == 0);
static_assert(offsetof(Counters, touchedListDispatch) == 0 && offsetof(Counters, blockDispatch) == 16 &&
              offsetof(Counters, listDispatch) == 32 && offsetof(Counters, collectDispatch) == 48 &&
              offsetof(Counters, retypeDispatch) == 64 && offsetof(Counters, vertexDispatch) == 80 &&
              offsetof(Counters, ownedDispatch) == 96 && offsetof(Counters, candidateDispatch) == 112 &&
              offsetof(Counters, releaseDispatch) == 128,
              "indirect arguments at 16-byte offsets");
static_assert(sizeof(Vertex) == 36 && offsetof(Vertex, nx) == 16 && offsetof(Vertex, color) == 32,
              "Vertex: 36-byte stride for renderers, normal at 16, colour at 32");
static_assert(offsetof(Counters, meshVerticesDropped) == offsetof(Counters, liveBlockCount) + 8);
static_assert(offsetof(Counters, exportUnreferenced) == offsetof(Counters, exportVertices) + 8);
static_assert(offsetof(Counters, validPixels) == COUNTERS_PER_FRAME_OFFSET);
static_assert(offsetof(Counters, freeTop) == COUNTERS_PER_FRAME_OFFSET + COUNTERS_PER_FRAME_SIZE,
              "per-frame counters are one contiguous range, cleared with one fill");
static_assert(offsetof(Counters, drawIndexed) % 4 == 0 && sizeof(Counters) == 432);
static_assert(sizeof(DeltaState) == 64 && sizeof(DeltaVertexRecord) == 36 && sizeof(DeltaTriangleRecord) == 16);
static_assert(sizeof(ModelViewState) == 64 && offsetof(ModelViewState, blockDispatch) == 32 && offsetof(ModelViewState, chunkDispatch) == 48);
static_assert(sizeof(ModelViewPush) == 112 && offsetof(ModelViewPush, blockSide) == 80 && offsetof(ModelViewPush, createdBefore) == 96,
              "ModelViewPush: the GLSL push block's layout");
static_assert(WG_VIEW_BLOCK * VIEW_CUBES_PER_INVOCATION == VOXELS_PER_BLOCK);
static_assert(sizeof(FramePush) == 128, "push constants: 128 bytes is all lavapipe guarantees");
static_assert(uint32_t(ColorFusion::Off) == COLOR_MODE_OFF && uint32_t(ColorFusion::Average) == COLOR_MODE_AVERAGE &&
              uint32_t(ColorFusion::Recent) == COLOR_MODE_RECENT);
static_assert(VOXELS_PER_BLOCK == BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE);
static_assert(VOXELS_PER_INVOCATION * WG_BLOCK == VOXELS_PER_BLOCK);
// A fusion invocation's corners are one four-corner element of the voxel arrays and one nibble of a mask word
// (cornerOfInvocation, block_store.glsl; toggleTsdfMasks, frame_lists.glsl).
static_assert(VOXELS_PER_INVOCATION == 4 && BLOCK_SIDE % VOXELS_PER_INVOCATION == 0);
static_assert(sizeof(TrackPush) == 96, "tracking push constants: at most 128 bytes, all lavapipe guarantees");
static_assert(sizeof(TrackParamsGpu) == 208 && offsetof(TrackParamsGpu, modelWorldToCamera) == 48 &&
                  offsetof(TrackParamsGpu, pixelsPerInvocation) == 96 && offsetof(TrackParamsGpu, lastTrackedCameraToWorld) == 112 &&
                  offsetof(TrackParamsGpu, recentRmse) == 188 && offsetof(TrackParamsGpu, minShareOfRecent) == 196,
              "TrackParamsGpu: std140 layout");
static_assert(sizeof(TrackStateGpu) == 208 && offsetof(TrackStateGpu, finalSums) == 64 && offsetof(TrackStateGpu, lostReason) == 192,
              "TrackStateGpu: std430 layout");
static_assert(sizeof(FramePoseGpu) == 112 && offsetof(FramePoseGpu, skip) == 96 && offsetof(FramePoseGpu, deintegrate) == 100, "FramePoseGpu: std430 layout");
static_assert(TRACK_SUM_MODEL_HITS + 1 == TRACK_SUM_COUNT && TRACK_SUM_JTR == 21 && WG_TRACK_REDUCE >= TRACK_SUM_COUNT);

}  // namespace vkmesh::gpu
