// Stage: triangulate (paper §V.D, §V.E; shaders_comp/triangulate/). Every cube of the retype list whose type
// changed releases its old triangles (refcount - 1; a vertex at 0 becomes a GC candidate) and builds its new
// type's triangles from the claimed edge slots into its chunk (popped when it had none); commit_chunks pops
// what was handed out.
//   reads  retype list, TSDF, hash, edge slots    writes cube state, chunks, refcounts, garbage lists
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class TriangulateStage {
public:
    TriangulateStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline triangulate_, commit_;
};

}  // namespace vkmesh::gpu
