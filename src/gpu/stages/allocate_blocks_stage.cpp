#include "gpu/stages/allocate_blocks_stage.h"

#include <cstddef>

#include "vk/commands.h"

namespace vkmesh::gpu {

AllocateBlocksStage::AllocateBlocksStage(const vk::Context& context, const vk::BindingTable& layout)
    : context_(context),
      layout_(layout),
      allocate_(context, layout, "allocate_blocks", FUSE_INTEGRATE),
      allocateTiles_(context, layout, "allocate_tiles", FUSE_INTEGRATE),
      assign_(context, layout, "assign_blocks"),
      commit_(context, layout, "commit_allocation") {}

void AllocateBlocksStage::record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters,
                                 uint32_t pixelStride, bool byTiles, bool deintegrate) const {
    if (deintegrate && !findForDeintegration_) {
        findForDeintegration_ = std::make_unique<vk::ComputePipeline>(context_, layout_, "allocate_blocks", FUSE_DEINTEGRATE);
        findTilesForDeintegration_ = std::make_unique<vk::ComputePipeline>(context_, layout_, "allocate_tiles", FUSE_DEINTEGRATE);
    }
    uint32_t width = ((push.imageSize & 0xFFFFu) + pixelStride - 1) / pixelStride;
    uint32_t height = (((push.imageSize >> 16) & FRAME_HEIGHT_MASK) + pixelStride - 1) / pixelStride;   // not FRAME_HAS_COLOR
    constexpr uint32_t groupHeight = WG_PIXELS_Y * ALLOC_COLUMN;   // sampled rows per workgroup
    if (byTiles) {
        const uint32_t tilesX = (width + ALLOC_TILE - 1) / ALLOC_TILE, tilesY = (height + ALLOC_TILE - 1) / ALLOC_TILE;
        (deintegrate ? *findTilesForDeintegration_ : allocateTiles_)
            .dispatch(cmd, &push, (tilesX + WG_PIXELS_X - 1) / WG_PIXELS_X, (tilesY + WG_PIXELS_Y - 1) / WG_PIXELS_Y);
        vk::memoryBarrier(cmd);
    }
    (deintegrate ? *findForDeintegration_ : allocate_).dispatch(cmd, &push, (width + WG_PIXELS_X - 1) / WG_PIXELS_X, (height + groupHeight - 1) / groupHeight);
    vk::memoryBarrier(cmd);
    assign_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, touchedListDispatch));
    vk::memoryBarrier(cmd);
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
