#include "gpu/stages/model_view_stage.h"

#include <cmath>
#include <cstddef>
#include <cstring>

#include "core/camera.h"

namespace vkmesh::gpu {

ModelViewStage::ModelViewStage(const vk::Context& context, const BlockStore& store, const BlockHash& hash, const CubeMesh& mesh,
                               float voxelSize)
    : context_(context),
      store_(store),
      hash_(hash),
      mesh_(mesh),
      blockSide_(voxelSize * float(BLOCK_SIDE)),
      table_(context, sizeof(ModelViewPush)),
      plan_(context, table_, "plan_model_view"),
      cullBlocks_(context, table_, "cull_view_blocks"),
      listChunks_(context, table_, "list_view_chunks"),
      emitTriangles_(context, table_, "emit_view_triangles") {
    state_ = makeStorage(context, table_, VIEW_BINDING_STATE, sizeof(ModelViewState), "model view state", VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT);
    follow();
}

void ModelViewStage::follow() {
    // Lists that cannot overflow: every live block, every chunk, every triangle slot of the heap.
    const VkDeviceSize blockBytes = VkDeviceSize(store_.capacity()) * 4, chunkBytes = VkDeviceSize(mesh_.chunkCapacity()) * 4;
    const VkDeviceSize indexBytes = VkDeviceSize(mesh_.chunkCapacity()) * CHUNK_WORDS * 4;
    if (blockList_.size() < blockBytes) blockList_ = makeStorage(context_, table_, VIEW_BINDING_BLOCK_LIST, blockBytes, "model view blocks");
    if (chunkList_.size() < chunkBytes) chunkList_ = makeStorage(context_, table_, VIEW_BINDING_CHUNK_LIST, chunkBytes, "model view chunks");
    if (indices_.size() < indexBytes)
        indices_ = makeStorage(context_, table_, VIEW_BINDING_INDICES, indexBytes, "model view indices", VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
    // Bound every time, not only when a handle changed: a buffer grown twice between two listings may get the
    // handle of one destroyed since, and a descriptor holds what its buffer was when it was written.
    table_.bind(VIEW_BINDING_BLOCK_COORDS, store_.coords());
    table_.bind(VIEW_BINDING_HASH_VALUES, hash_.values());
    table_.bind(VIEW_BINDING_CUBE_STATE, mesh_.cubeStates());
    table_.bind(VIEW_BINDING_CHUNKS, mesh_.chunkTriangles());
    table_.bind(VIEW_BINDING_VERTICES, mesh_.vertices());
}

void ModelViewStage::record(VkCommandBuffer cmd, const Pose& cameraToWorld, const Intrinsics& intrinsics, int width, int height,
                            float nearDepth, float farDepth, uint32_t createdBefore) {
    follow();
    ModelViewPush push{};
    const RigidRows rows = rigidRows(inverseRigid(cameraToWorld));
    std::memcpy(push.worldToCamera, rows.r, sizeof(push.worldToCamera));
    push.intrinsics[0] = intrinsics.fx, push.intrinsics[1] = intrinsics.fy;
    push.intrinsics[2] = intrinsics.cx, push.intrinsics[3] = intrinsics.cy;
    push.viewport[0] = float(width), push.viewport[1] = float(height);
    push.viewport[2] = nearDepth, push.viewport[3] = farDepth;
    push.blockSide = blockSide_;
    // Half the block's diagonal, and a hundredth of it and a micrometre against the rounding of positions.
    push.blockRadius = 0.5f * blockSide_ * std::sqrt(3.0f) * 1.01f + 1e-6f;
    push.blockCapacity = store_.capacity();
    push.hashCapacity = hash_.capacity();
    push.createdBefore = createdBefore;
    // The volume's writes (its passes, its transfers) before the listing reads them, and the last draw's reads of
    // the lists and the command before the listing rewrites them.
    VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    before.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    before.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT |
                             VK_PIPELINE_STAGE_VERTEX_INPUT_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &before, 0, nullptr, 0, nullptr);
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    cullBlocks_.dispatchItems(cmd, &push, push.blockCapacity);
    vk::memoryBarrier(cmd);
    listChunks_.dispatchIndirect(cmd, &push, state_, offsetof(ModelViewState, blockDispatch));
    vk::memoryBarrier(cmd);
    emitTriangles_.dispatchIndirect(cmd, &push, state_, offsetof(ModelViewState, chunkDispatch));
}

std::vector<std::array<uint32_t, 3>> ModelViewStage::downloadList() const {
    ModelViewState state{};
    vk::downloadFromBuffer(context_, state_, &state, sizeof(state));
    std::vector<std::array<uint32_t, 3>> triangles(state.draw[0] / 3);
    if (!triangles.empty()) vk::downloadFromBuffer(context_, indices_, triangles.data(), triangles.size() * sizeof(triangles[0]));
    return triangles;
}

}  // namespace vkmesh::gpu
