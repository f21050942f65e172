// Fixtures the tests of the CPU reference mesher share (test_reference_mesher.cpp,
// test_reference_mesher_refinement.cpp): the small volume, the room, depth rendering and the from-scratch check.
#pragma once

#include "cpu/reference_mesher.h"

#include <gtest/gtest.h>

#include "test_support.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh_analysis.h"
#include "cpu/reference_volume.h"
#include "synth/synthetic_scene.h"

namespace vkmesh::test::reference_mesher_fixtures {

inline constexpr int kWidth = 160, kHeight = 120;

inline VolumeParams smallParams(float voxel = 0.04f) {
    VolumeParams p;
    p.voxelSize = voxel;
    p.truncVoxels = 4;
    p.maxDepth = 6.0f;
    return p;
}

inline DepthImage render(const synth::SyntheticScene& scene, const Pose& pose, bool noise, uint32_t seed) {
    synth::RenderOptions options;
    options.noise = noise;
    options.seed = seed;
    return scene.renderDepth(synth::kinectIntrinsics(kWidth, kHeight), pose, options);
}

inline const synth::SyntheticScene& room() {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    return scene;
}

// The incremental mesh of `mesher` against a from-scratch extraction on the same TSDF: same triangles (as
// position triples, exactly), same vertex count, same normals (same float operations).
inline void expectEqualsFromScratch(const cpu::ReferenceMesher& mesher, const cpu::ReferenceVolume& volume,
                             const VolumeParams& params, uint32_t frame, const std::string& when) {
    cpu::ReferenceMesher fresh(params, 1.0f, 1u << 18, 1u << 18, mesher.options());
    const cpu::MeshFrameStats s = fresh.updateAll(volume, frame);
    EXPECT_EQ(s.vertexExhausted + s.chunkExhausted + s.trianglesInvalid, 0u) << when;
    EXPECT_TRUE(fresh.checkInvariants().empty()) << when << "\n" << joined(fresh.checkInvariants());
    const Mesh ours = mesher.exportMesh(frame), scratch = fresh.exportMesh(frame);
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(ours), canonicalTriangles(scratch), 0), 0u)
        << when << ": " << ours.triangles.size() << " incremental vs " << scratch.triangles.size() << " from scratch";
    EXPECT_EQ(ours.positions.size(), scratch.positions.size()) << when;
    EXPECT_EQ(ours.triangles.size(), scratch.triangles.size()) << when;
    // The same (position, normal) multiset (positions are unique, refined too; the normals are compared as well).
    auto vertexSet = [](const Mesh& m) {
        std::vector<std::array<float, 6>> out;
        for (size_t i = 0; i < m.positions.size(); ++i)
            out.push_back({m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), m.normals[i].x(), m.normals[i].y(), m.normals[i].z()});
        std::sort(out.begin(), out.end());
        return out;
    };
    EXPECT_TRUE(vertexSet(ours) == vertexSet(scratch)) << when << ": vertices (position, normal) differ from the from-scratch ones";
}

inline cpu::MesherOptions mesherOptions(bool refine, bool lockFree) {
    cpu::MesherOptions o;
    o.refine = refine;
    o.lockFree = lockFree;
    return o;
}

}  // namespace vkmesh::test::reference_mesher_fixtures
