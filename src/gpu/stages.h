// The stages of vkmesh's GPU frame pipeline. Each stage is one host class that owns its compute
// pipelines (shaders_comp/<name>.comp) and records its dispatches; the data structure they work on
// (src/gpu/gpu_volume.h) owns the buffers. Stages are separated by full memory barriers.
#pragma once

#include "gpu/layout.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

// Paper §V.A, second half: one workgroup per touched block updates its 512 TSDF corners.
class FuseDepthStage {
public:
    FuseDepthStage(const vk::Context& context, const vk::BindingTable& layout);
    void record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const;

private:
    vk::ComputePipeline fuse_;
};

// The Chisel-style baseline mesh: list every live block (collect_blocks, plan_block_list), then
// marching cubes in every cube, 3 vertices of its own per triangle (mesh_baseline).
class BaselineMeshStage {
public:
    BaselineMeshStage(const vk::Context& context, const vk::BindingTable& layout);
    // Lists every live block (blockList, liveBlockCount) and sizes listDispatch; other passes use it too.
    void recordCollect(VkCommandBuffer cmd, const FramePush& push, uint32_t hashCapacity) const;
    void record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters, uint32_t hashCapacity) const;

private:
    vk::ComputePipeline collect_, plan_, mesh_;
};

// The incremental shared-vertex mesh (docs/MESH.md), recorded after fusion every frame: list the dirty
// blocks (mark_dirty, or mark_all_dirty for a from-scratch pass) and the cubes that may change type
// (plan_mesh, collect_retype, plan_retype), claim edge vertices (mesh_claim, commit_vertices), move the
// dirty blocks' vertices and the new ones (update_vertices + update_new_vertices, or update_heap_vertices),
// rebuild changed cubes' triangles (mesh_triangulate, commit_chunks), collect garbage (free_vertices, free_chunks, commit_free).
class IncrementalMeshStage {
public:
    IncrementalMeshStage(const vk::Context& context, const vk::BindingTable& layout);
    // Dirty = blocks touched this frame and their -x/-y/-z neighbours.
    void recordMarkTouched(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const;
    // Dirty = every block listed by collect_blocks (record BaselineMeshStage::recordCollect first).
    void recordMarkAll(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;
    // Also dirty: every listed block with retype bits left over (INCOMPLETE cubes, deferred cubes). After
    // mark_dirty; needs the live block list.
    void recordMarkPending(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;
    // lockFree: the claim pass runs as 4 dispatches by cube parity class, without atomics on edge slots.
    void recordMesh(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters, vk::StageTimer* timer,
                    bool lockFree) const;

private:
    vk::ComputePipeline markDirty_, markAllDirty_, markPending_, plan_, collect_, planRetype_, claim_, claimClass0_, claimClass1_,
        claimClass2_, claimClass3_, commitVertices_, update_, updateNew_, updateHeap_, triangulate_, commitChunks_, freeVertices_, freeChunks_,
        commitFree_;
};

// Bounded maps (docs/MESH.md, "Recycling blocks"). Phase 1 (recordRetire, after fusion and mark_dirty,
// before the mesh passes) zeroes the weights of blocks beyond the keep radius and decays those of idle
// blocks, marking the cubes that read corners which stop being observed; phase 2 (recordFree, after the
// mesh passes) frees the blocks left with no weight and no mesh state. Both run over the live block list
// (BaselineMeshStage::recordCollect). The tombstones freed keys leave in the hash are dropped by
// BlockHash::recordRebuild (src/gpu/block_hash.h).
class RecycleStage {
public:
    RecycleStage(const vk::Context& context, const vk::BindingTable& layout);
    void recordRetire(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const;
    void recordFree(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const;

private:
    vk::ComputePipeline retire_, free_, commitFree_;
};

// Compaction of the shared-vertex mesh into dense vertex and index buffers (plan_export, export_vertices,
// export_triangles; each over the used part of its heap), and the indirect draw command of the result
// (finish_export).
class ExportMeshStage {
public:
    ExportMeshStage(const vk::Context& context, const vk::BindingTable& layout);
    void record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters) const;

private:
    vk::ComputePipeline plan_, vertices_, triangles_, finish_;
};

// Mesh deltas (docs/DELTAS.md): what changed in the vertex heap and the triangle chunks since the last
// report, by comparison with shadow copies (plan_deltas, diff_vertices, diff_triangles). Its own binding
// layout (DELTA_BINDING_*), no push constants.
class MeshDeltaStage {
public:
    MeshDeltaStage(const vk::Context& context, const vk::BindingTable& deltaLayout);
    void record(VkCommandBuffer cmd, const vk::Buffer& deltaState) const;

private:
    vk::ComputePipeline plan_, vertices_, triangles_;
};

}  // namespace vkmesh::gpu
