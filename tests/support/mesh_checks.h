// Checks of the shared-vertex mesh shared by the GPU tests: the exported mesh as a triangle soup, and the
// invariants of docs/MESH.md on the raw GPU state.
#pragma once

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "gpu/gpu_volume.h"
#include "synth/synthetic_scene.h"

namespace vkmesh::test {

// The volume most GPU mesh tests use: the synthetic room at 160 x 120, 4 cm voxels, heaps roomy enough
// that nothing runs out unless a test shrinks them.
inline gpu::GpuVolumeConfig smallRoomConfig() {
    gpu::GpuVolumeConfig c;
    c.params.voxelSize = 0.04f;
    c.params.maxDepth = 6.0f;
    c.blockCapacity = 4096;
    c.vertexCapacity = 1u << 17;
    c.chunkCapacity = 1u << 17;
    c.imageWidth = 160;
    c.imageHeight = 120;
    return c;
}

inline std::vector<Eigen::Vector3f> soupOf(const gpu::ExportedMesh& mesh) {
    std::vector<Eigen::Vector3f> soup;
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) soup.emplace_back(mesh.vertices[v].px, mesh.vertices[v].py, mesh.vertices[v].pz);
    return soup;
}

// Checks every invariant of docs/MESH.md on the raw GPU state; returns the problems found.
inline std::vector<std::string> checkInvariants(const gpu::MeshStateSnapshot& s, const gpu::GpuVolumeConfig& config) {
    std::vector<std::string> problems;
    auto fail = [&](const std::string& p) { if (problems.size() < 10) problems.push_back(p); };
    std::vector<uint32_t> uses(s.vertices.size(), 0);
    for (const auto& t : s.liveTriangles)
        for (uint32_t v : t) {
            if (v >= s.vertices.size()) { fail("triangle uses vertex " + std::to_string(v) + " out of range"); continue; }
            ++uses[v];
        }
    uint32_t live = 0;
    for (uint32_t v = 0; v < s.vertices.size(); ++v) {
        uint32_t refs = s.vertices[v].refcount;
        if (refs == gpu::DEAD_REFCOUNT) {
            if (uses[v]) fail("free vertex " + std::to_string(v) + " used by " + std::to_string(uses[v]) + " triangles");
            continue;
        }
        ++live;
        if (refs != uses[v]) fail("vertex " + std::to_string(v) + " refcount " + std::to_string(refs) + " but " + std::to_string(uses[v]) + " triangles");
        if (refs == 0) fail("vertex " + std::to_string(v) + " alive without triangles");
        if (s.vertexOwner[v] >= s.edgeVertex.size() || s.edgeVertex[s.vertexOwner[v]] != v)
            fail("vertex " + std::to_string(v) + "'s owner slot does not point back");
    }
    for (size_t slot = 0; slot < s.edgeVertex.size(); ++slot) {
        uint32_t v = s.edgeVertex[slot];
        if (v == gpu::EMPTY_SLOT) continue;
        if (v >= s.vertices.size() || s.vertices[v].refcount == gpu::DEAD_REFCOUNT || s.vertexOwner[v] != slot)
            fail("edge slot " + std::to_string(slot) + " holds " + std::to_string(v) + ", not a live vertex it owns");
    }
    // The owned-slot masks (cube_mesh.glsl): a bit set exactly for each slot that holds a vertex.
    const size_t blocks = s.edgeVertex.size() / (3 * gpu::VOXELS_PER_BLOCK);
    if (s.ownedSlots.size() != blocks * gpu::OWNED_SLOT_WORDS) {
        fail("owned-slot masks: " + std::to_string(s.ownedSlots.size()) + " words for " + std::to_string(blocks) + " blocks");
    } else {
        size_t wrong = 0, first = 0;
        for (size_t slot = 0; slot < s.edgeVertex.size(); ++slot) {
            const size_t cube = slot / 3, axis = slot % 3;
            const size_t word = (cube / gpu::VOXELS_PER_BLOCK) * gpu::OWNED_SLOT_WORDS + axis * gpu::MASK_WORDS + (cube % gpu::VOXELS_PER_BLOCK) / 32;
            const bool bit = (s.ownedSlots[word] >> (cube % 32)) & 1u;
            if (bit != (s.edgeVertex[slot] != gpu::EMPTY_SLOT) && wrong++ == 0) first = slot;
        }
        if (wrong)
            fail("owned-slot masks disagree with the edge slots at " + std::to_string(wrong) + " slots (first: slot " + std::to_string(first) +
                 " holds " + std::to_string(s.edgeVertex[first]) + ")");
    }
    const gpu::Counters& k = s.counters;
    if (live != k.verticesInUse) fail("verticesInUse " + std::to_string(k.verticesInUse) + " but " + std::to_string(live) + " live");
    if (k.vertexFreeTop + k.verticesInUse != config.vertexCapacity) fail("vertex heap: free + in use != capacity");
    if (k.chunkFreeTop + k.chunksInUse != config.chunkCapacity) fail("chunk heap: free + in use != capacity");
    if (k.freeTop + k.blocksInUse != config.blockCapacity) fail("block pool: free + in use != capacity");
    if (k.liveTriangles != s.liveTriangles.size())
        fail("liveTriangles " + std::to_string(k.liveTriangles) + " but " + std::to_string(s.liveTriangles.size()) + " found");
    return problems;
}

// Frames [from, to) of the noisy 24-frame orbit around the synthetic room at 160 x 120, with its textures' colour,
// fused at their true poses: the same frame i whoever fuses it, so runs split anywhere add up to one run.
inline void integrateNoisyRoomOrbit(gpu::GpuVolume& volume, size_t from, size_t to) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intr = synth::kinectIntrinsics(160, 120);
    const auto poses = synth::cameraPath(24, synth::PathKind::Orbit);
    for (size_t i = from; i < to; ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        const Pose& pose = poses[i % poses.size()];
        ColorImage color;
        const DepthImage depth = scene.renderDepth(intr, pose, options, &color);
        const gpu::FrameReport r = volume.integrate(depth, &color, intr, pose);
        EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
    }
}

}  // namespace vkmesh::test
