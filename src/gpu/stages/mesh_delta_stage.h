// Stage: mesh deltas (docs/DELTAS.md; shaders_comp/deltas/): what changed in the vertex heap and the
// triangle chunks since the last report, by comparison with shadow copies (plan_deltas, diff_vertices,
// diff_triangles). It owns the shadows, its state and the record lists, in a binding table of its own
// (DELTA_BINDING_*, no push constants), and grows the shadows with the heaps and the lists on demand.
//   reads  counters, vertex heap, chunks    writes shadows, records, DeltaState
#pragma once

#include "core/mesh_delta.h"
#include "gpu/structure/counter_buffer.h"
#include "gpu/structure/cube_mesh.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class MeshDeltaStage {
public:
    MeshDeltaStage(const vk::Context& context, const CounterBuffer& counters, const CubeMesh& mesh, uint32_t recordCapacity);
    // Records the passes and the copy of their state to the host.
    void record(VkCommandBuffer cmd);
    // After a submission with record(): downloads the records, growing the lists and re-running the passes
    // (in `recorder`'s own submissions) until everything fitted.
    MeshDelta collect(vk::CommandRecorder& recorder);
    // After the heaps grew: larger shadows (new entries: dead vertices, empty triangle slots, as the heaps'
    // new entries are) and the heaps' new buffers bound.
    void followHeaps(const CubeMesh& mesh);
    void pools(std::vector<PoolInfo>& out) const {
        listPools(out, {&prevVertices_, &prevChunks_, &state_, &vertexRecords_, &triangleRecords_, &stateReadback_});
    }

private:
    const vk::Context& context_;
    vk::BindingTable table_;
    vk::ComputePipeline plan_, vertices_, triangles_;
    vk::Buffer prevVertices_, prevChunks_, state_, vertexRecords_, triangleRecords_, stateReadback_;
};

}  // namespace vkmesh::gpu
