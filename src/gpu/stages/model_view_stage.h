// Stage: the model in a view (shaders_comp/model_view/; docs/TRACKING.md, "Only the model in view"). Lists the
// triangles of the live blocks that can be in a camera's view into an index buffer over the vertex heap, with the
// indirect draw of that list, so that tracking's draw of the model costs what is in view instead of the whole
// map, and needs no compacted copy of the mesh (the export). Owns its lists and state, in a binding table of its
// own (VIEW_BINDING_*, ModelViewPush); reads the volume's buffers, whichever they are when it records (they are
// replaced when the volume grows).
//   reads  block coords, hash values, cube states, chunks, vertices' ages    writes its block, chunk and index lists, ModelViewState
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/types.h"
#include "gpu/layout.h"
#include "gpu/structure/block_hash.h"
#include "gpu/structure/block_store.h"
#include "gpu/structure/cube_mesh.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class ModelViewStage {
public:
    ModelViewStage(const vk::Context& context, const BlockStore& store, const BlockHash& hash, const CubeMesh& mesh, float voxelSize);
    // Records the listing for the view of a `width` x `height` camera with `intrinsics` at `cameraToWorld`, depths in
    // [near, far]: indices() over the vertex heap, and its VkDrawIndexedIndirectCommand at drawOffset() in state().
    // Only triangles whose three vertices were created before frame number `createdBefore` are listed (UINT32_MAX: all).
    // Between submissions only (it may rebind and reallocate its buffers). The caller records the barrier for the draw.
    void record(VkCommandBuffer cmd, const Pose& cameraToWorld, const Intrinsics& intrinsics, int width, int height,
                float nearDepth, float farDepth, uint32_t createdBefore = UINT32_MAX);
    // After the submission of a record(): the triangles it listed (vertex heap indices), for tests.
    std::vector<std::array<uint32_t, 3>> downloadList() const;
    const vk::Buffer& indices() const { return indices_; }
    const vk::Buffer& state() const { return state_; }
    static constexpr VkDeviceSize drawOffset() { return offsetof(ModelViewState, draw); }
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&blockList_, &chunkList_, &indices_, &state_}); }

private:
    // The volume's current buffers bound, and lists as large as its current capacities.
    void follow();

    const vk::Context& context_;
    const BlockStore& store_;
    const BlockHash& hash_;
    const CubeMesh& mesh_;
    float blockSide_;
    vk::BindingTable table_;
    vk::ComputePipeline plan_, cullBlocks_, listChunks_, emitTriangles_;
    vk::Buffer blockList_, chunkList_, indices_, state_;
};

}  // namespace vkmesh::gpu
