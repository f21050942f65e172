#include "gpu/stages/mesh_delta_stage.h"

#include <cstddef>
#include <cstring>

namespace vkmesh::gpu {

MeshDeltaStage::MeshDeltaStage(const vk::Context& context, const CounterBuffer& counters, const CubeMesh& mesh, uint32_t recordCapacity)
    : context_(context),
      table_(context, 0),
      plan_(context, table_, "plan_deltas"),
      vertices_(context, table_, "diff_vertices"),
      triangles_(context, table_, "diff_triangles") {
    prevVertices_ = makeStorage(context, table_, DELTA_BINDING_PREV_VERTICES, mesh.vertices().size(), "vertex heap shadow");
    prevChunks_ = makeStorage(context, table_, DELTA_BINDING_PREV_CHUNKS, mesh.chunkTriangles().size(), "triangle chunk shadow");
    state_ = makeStorage(context, table_, DELTA_BINDING_STATE, sizeof(DeltaState), "delta state", VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT);
    vertexRecords_ = makeStorage(context, table_, DELTA_BINDING_VERTEX_RECORDS, VkDeviceSize(recordCapacity) * sizeof(DeltaVertexRecord),
                                 "vertex delta records");
    triangleRecords_ = makeStorage(context, table_, DELTA_BINDING_TRIANGLE_RECORDS,
                                   VkDeviceSize(recordCapacity) * sizeof(DeltaTriangleRecord), "triangle delta records");
    table_.bind(DELTA_BINDING_COUNTERS, counters.buffer());
    table_.bind(DELTA_BINDING_VERTICES, mesh.vertices());
    table_.bind(DELTA_BINDING_CHUNKS, mesh.chunkTriangles());
    stateReadback_ = vk::Buffer(context, sizeof(DeltaState), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "delta state readback");
    DeltaState state{};
    state.vertexRecordCapacity = state.triangleRecordCapacity = recordCapacity;
    vk::uploadToBuffer(context, state_, &state, sizeof(state));
    // The shadows start as an empty mesh: every vertex dead, every triangle slot empty.
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    vkCmdFillBuffer(cmd, prevVertices_.handle(), 0, VK_WHOLE_SIZE, DEAD_REFCOUNT);
    vkCmdFillBuffer(cmd, prevChunks_.handle(), 0, VK_WHOLE_SIZE, INVALID_INDEX);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
}

void MeshDeltaStage::record(VkCommandBuffer cmd) {
    plan_.dispatch(cmd, nullptr, 1);
    vk::memoryBarrier(cmd);
    vertices_.dispatchIndirect(cmd, nullptr, state_, offsetof(DeltaState, vertexDispatch));
    triangles_.dispatchIndirect(cmd, nullptr, state_, offsetof(DeltaState, triangleDispatch));
    vk::memoryBarrier(cmd);
    VkBufferCopy region{0, 0, sizeof(DeltaState)};
    vkCmdCopyBuffer(cmd, state_.handle(), stateReadback_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

MeshDelta MeshDeltaStage::collect(vk::CommandRecorder& recorder) {
    MeshDelta delta;
    // Each pass lists what fits and updates the shadows of only what it listed, so a re-run after growing
    // the lists finds exactly the rest. The number of records is bounded by the heaps: 3 passes suffice.
    for (int pass = 0; pass < 3; ++pass) {
        DeltaState state{};
        stateReadback_.invalidate();
        std::memcpy(&state, stateReadback_.mapped(), sizeof(state));
        const uint32_t nv = std::min(state.vertexRecords, state.vertexRecordCapacity);
        const uint32_t nt = std::min(state.triangleRecords, state.triangleRecordCapacity);
        const size_t v0 = delta.vertices.size(), t0 = delta.triangles.size();
        delta.vertices.resize(v0 + nv);
        delta.triangles.resize(t0 + nt);
        if (nv) vk::downloadFromBuffer(context_, vertexRecords_, &delta.vertices[v0], nv * sizeof(DeltaVertexRecord));
        if (nt) vk::downloadFromBuffer(context_, triangleRecords_, &delta.triangles[t0], nt * sizeof(DeltaTriangleRecord));
        if (state.vertexRecords <= state.vertexRecordCapacity && state.triangleRecords <= state.triangleRecordCapacity) return delta;
        // Grow the lists that overflowed to what was missing, with headroom, and run the passes again.
        if (state.vertexRecords > state.vertexRecordCapacity) {
            state.vertexRecordCapacity = state.vertexRecords + state.vertexRecords / 2;
            vertexRecords_ = makeStorage(context_, table_, DELTA_BINDING_VERTEX_RECORDS,
                                         VkDeviceSize(state.vertexRecordCapacity) * sizeof(DeltaVertexRecord), "vertex delta records");
        }
        if (state.triangleRecords > state.triangleRecordCapacity) {
            state.triangleRecordCapacity = state.triangleRecords + state.triangleRecords / 2;
            triangleRecords_ = makeStorage(context_, table_, DELTA_BINDING_TRIANGLE_RECORDS,
                                           VkDeviceSize(state.triangleRecordCapacity) * sizeof(DeltaTriangleRecord), "triangle delta records");
        }
        vk::uploadToBuffer(context_, state_, &state.vertexRecordCapacity, 2 * sizeof(uint32_t), offsetof(DeltaState, vertexRecordCapacity));
        VkCommandBuffer cmd = recorder.begin();
        record(cmd);
        recorder.submitAndWait();
    }
    throw Error("mesh deltas did not fit after growing their lists");
}

void MeshDeltaStage::followHeaps(const CubeMesh& mesh) {
    std::vector<vk::Buffer> retired;
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    if (prevVertices_.size() < mesh.vertices().size())
        growStorage(cmd, context_, table_, DELTA_BINDING_PREV_VERTICES, prevVertices_, mesh.vertices().size(), DEAD_REFCOUNT, retired);
    if (prevChunks_.size() < mesh.chunkTriangles().size())
        growStorage(cmd, context_, table_, DELTA_BINDING_PREV_CHUNKS, prevChunks_, mesh.chunkTriangles().size(), INVALID_INDEX, retired);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    table_.bind(DELTA_BINDING_VERTICES, mesh.vertices());
    table_.bind(DELTA_BINDING_CHUNKS, mesh.chunkTriangles());
}

}  // namespace vkmesh::gpu
