// What two runs that must end alike are compared by (map files, paging): every block's TSDF bits and colour words
// by coordinate, the mesh as a set of triangles, and each vertex's position bits with its age, refcount and colour.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <tuple>
#include <vector>

#include "core/mesh_analysis.h"
#include "gpu/gpu_volume.h"
#include "mesh_checks.h"

namespace vkmesh::test {

// What must be equal: every live block's TSDF bits and colour words (by coordinate), the mesh as a set of
// triangles, and each vertex's position bits with its age, refcount and colour.
struct State {
    std::map<std::tuple<int, int, int>, std::pair<std::vector<float>, std::vector<float>>> tsdf;
    std::map<std::tuple<int, int, int>, std::vector<uint32_t>> color;
    std::vector<CanonicalTriangle> triangles;
    std::vector<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t, uint32_t, uint32_t>> vertices;   // position bits, createdFrame, refcount, colour
    uint32_t frameNumber = 0;
};

inline State stateOf(gpu::GpuVolume& volume) {
    State s;
    for (auto& b : volume.downloadBlocks()) {
        s.color[{b.coord.x(), b.coord.y(), b.coord.z()}] = std::move(b.color);
        s.tsdf[{b.coord.x(), b.coord.y(), b.coord.z()}] = {std::move(b.sdf), std::move(b.weight)};
    }
    const gpu::ExportedMesh mesh = volume.exportMesh();
    s.triangles = canonicalTriangles(test::soupOf(mesh));
    for (const gpu::Vertex& v : mesh.vertices) {
        uint32_t p[3];
        std::memcpy(p, &v.px, 12);
        s.vertices.emplace_back(p[0], p[1], p[2], v.createdFrame, v.refcount, v.color);
    }
    std::sort(s.vertices.begin(), s.vertices.end());
    s.frameNumber = volume.frameNumber();
    return s;
}

inline void expectSameState(const State& a, const State& b, bool sameAges = true) {
    ASSERT_EQ(a.tsdf.size(), b.tsdf.size());
    size_t differingBlocks = 0;
    for (const auto& [coord, values] : a.tsdf) {
        auto it = b.tsdf.find(coord);
        ASSERT_NE(it, b.tsdf.end()) << "a block missing after the resume";
        const bool same = values.first.size() == it->second.first.size() &&
                          std::memcmp(values.first.data(), it->second.first.data(), values.first.size() * 4) == 0 &&
                          std::memcmp(values.second.data(), it->second.second.data(), values.second.size() * 4) == 0;
        differingBlocks += !same;
    }
    EXPECT_EQ(differingBlocks, 0u) << "blocks whose TSDF bits differ";
    EXPECT_TRUE(a.color == b.color) << "colour words differ";
    size_t colored = 0;
    for (const auto& [coord, words] : a.color) colored += std::count_if(words.begin(), words.end(), [](uint32_t w) { return w != 0; });
    EXPECT_GT(colored, 1000u) << "the run fused colour";
    EXPECT_GT(a.triangles.size(), 1000u);
    EXPECT_EQ(countTriangleMismatches(a.triangles, b.triangles, 0), 0u);
    EXPECT_EQ(a.triangles.size(), b.triangles.size());
    if (sameAges) {
        EXPECT_EQ(a.frameNumber, b.frameNumber);
        ASSERT_EQ(a.vertices.size(), b.vertices.size());
        size_t differing = 0;
        for (size_t i = 0; i < a.vertices.size(); ++i)
            if (a.vertices[i] != b.vertices[i]) {
                if (differing++ < 3)
                    ADD_FAILURE() << "vertex " << i << ": " << std::get<0>(a.vertices[i]) << "," << std::get<1>(a.vertices[i]) << ","
                                  << std::get<2>(a.vertices[i]) << " age " << std::get<3>(a.vertices[i]) << " ref " << std::get<4>(a.vertices[i])
                                  << " vs " << std::get<0>(b.vertices[i]) << "," << std::get<1>(b.vertices[i]) << "," << std::get<2>(b.vertices[i])
                                  << " age " << std::get<3>(b.vertices[i]) << " ref " << std::get<4>(b.vertices[i]);
            }
        EXPECT_EQ(differing, 0u) << "vertices whose position bits, age or refcount differ";
    } else {
        EXPECT_EQ(a.vertices.size(), b.vertices.size());
    }
}

}  // namespace vkmesh::test
