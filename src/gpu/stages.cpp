#include "gpu/stages.h"

#include <cstddef>

#include "vk/commands.h"

namespace vkmesh::gpu {

FuseDepthStage::FuseDepthStage(const vk::Context& context, const vk::BindingTable& layout)
    : fuse_(context, layout, "fuse_depth") {}

void FuseDepthStage::record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const {
    fuse_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, blockDispatch));
    vk::memoryBarrier(cmd);
}

BaselineMeshStage::BaselineMeshStage(const vk::Context& context, const vk::BindingTable& layout)
    : collect_(context, layout, "collect_blocks"),
      plan_(context, layout, "plan_block_list"),
      mesh_(context, layout, "mesh_baseline") {}

void BaselineMeshStage::recordCollect(VkCommandBuffer cmd, const FramePush& push, uint32_t hashCapacity) const {
    collect_.dispatch(cmd, &push, (hashCapacity + WG_LIST - 1) / WG_LIST);
    vk::memoryBarrier(cmd);
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

void BaselineMeshStage::record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters,
                               uint32_t hashCapacity) const {
    recordCollect(cmd, push, hashCapacity);
    mesh_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
}

IncrementalMeshStage::IncrementalMeshStage(const vk::Context& context, const vk::BindingTable& layout)
    : markDirty_(context, layout, "mark_dirty"),
      markAllDirty_(context, layout, "mark_all_dirty"),
      markPending_(context, layout, "mark_pending_dirty"),
      plan_(context, layout, "plan_mesh"),
      collect_(context, layout, "collect_retype"),
      planRetype_(context, layout, "plan_retype"),
      claim_(context, layout, "mesh_claim"),
      claimClass0_(context, layout, "mesh_claim", 0u),
      claimClass1_(context, layout, "mesh_claim", 1u),
      claimClass2_(context, layout, "mesh_claim", 2u),
      claimClass3_(context, layout, "mesh_claim", 3u),
      commitVertices_(context, layout, "commit_vertices"),
      update_(context, layout, "update_vertices"),
      updateNew_(context, layout, "update_new_vertices"),
      updateHeap_(context, layout, "update_heap_vertices"),
      triangulate_(context, layout, "mesh_triangulate"),
      commitChunks_(context, layout, "commit_chunks"),
      freeVertices_(context, layout, "free_vertices"),
      freeChunks_(context, layout, "free_chunks"),
      commitFree_(context, layout, "commit_free") {}

void IncrementalMeshStage::recordMarkTouched(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const {
    // assignDispatch covers the touched list (sized by plan_frame).
    markDirty_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, assignDispatch));
    vk::memoryBarrier(cmd);
}

void IncrementalMeshStage::recordMarkAll(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    markAllDirty_.dispatch(cmd, &push, (blockCapacity + WG_LIST - 1) / WG_LIST);
    vk::memoryBarrier(cmd);
}

void IncrementalMeshStage::recordMarkPending(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    markPending_.dispatch(cmd, &push, (blockCapacity + WG_LIST - 1) / WG_LIST);
    vk::memoryBarrier(cmd);
}

void IncrementalMeshStage::recordMesh(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters,
                                      vk::StageTimer* timer, bool lockFree) const {
    auto mark = [&](const char* name) { if (timer) timer->mark(cmd, name); };
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    collect_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, collectDispatch));
    vk::memoryBarrier(cmd);
    planRetype_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    if (lockFree) {
        for (const vk::ComputePipeline* claim : {&claimClass0_, &claimClass1_, &claimClass2_, &claimClass3_}) {
            claim->dispatchIndirect(cmd, &push, counters, offsetof(Counters, retypeDispatch));
            vk::memoryBarrier(cmd);
        }
    } else {
        claim_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, retypeDispatch));
        vk::memoryBarrier(cmd);
    }
    commitVertices_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    mark("mesh_claim");
    update_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, vertexDispatch));
    vk::memoryBarrier(cmd);
    updateNew_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, candidateDispatch));
    vk::memoryBarrier(cmd);
    updateHeap_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, heapDispatch));
    vk::memoryBarrier(cmd);
    mark("mesh_update");
    triangulate_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, retypeDispatch));
    vk::memoryBarrier(cmd);
    commitChunks_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    mark("mesh_triangulate");
    freeVertices_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, candidateDispatch));
    vk::memoryBarrier(cmd);
    freeChunks_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, releaseDispatch));
    vk::memoryBarrier(cmd);
    commitFree_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    mark("mesh_gc");
}

RecycleStage::RecycleStage(const vk::Context& context, const vk::BindingTable& layout)
    : retire_(context, layout, "recycle_retire"),
      free_(context, layout, "recycle_free"),
      commitFree_(context, layout, "commit_recycle") {}

void RecycleStage::recordRetire(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const {
    retire_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
}

void RecycleStage::recordFree(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const {
    free_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
    commitFree_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

ExportMeshStage::ExportMeshStage(const vk::Context& context, const vk::BindingTable& layout)
    : plan_(context, layout, "plan_export"),
      vertices_(context, layout, "export_vertices"),
      triangles_(context, layout, "export_triangles"),
      finish_(context, layout, "finish_export") {}

void ExportMeshStage::record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const {
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    vertices_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, exportDispatch));
    vk::memoryBarrier(cmd);
    triangles_.dispatchIndirect(cmd, &push, counters, offsetof(Counters, exportTriangleDispatch));
    vk::memoryBarrier(cmd);
    finish_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

MeshDeltaStage::MeshDeltaStage(const vk::Context& context, const vk::BindingTable& deltaLayout)
    : plan_(context, deltaLayout, "plan_deltas"),
      vertices_(context, deltaLayout, "diff_vertices"),
      triangles_(context, deltaLayout, "diff_triangles") {}

void MeshDeltaStage::record(VkCommandBuffer cmd, const vk::Buffer& deltaState) const {
    plan_.dispatch(cmd, nullptr, 1);
    vk::memoryBarrier(cmd);
    vertices_.dispatchIndirect(cmd, nullptr, deltaState, offsetof(DeltaState, vertexDispatch));
    triangles_.dispatchIndirect(cmd, nullptr, deltaState, offsetof(DeltaState, triangleDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
