// Map algebra on a GPU volume (docs/SCALING.md): the frames of one run split into parts, each part fused into a
// map of its own, and the maps merged (mergeMaps), give the map of the one run: TSDF bits (sums, counts), the
// triangle set, vertex position and normal bits, and colour within one 8-bit level. Meshed tile by tile, each tile
// alone on the GPU, the tiles joined are that mesh: no seam, no vertex twice. The host side (what adds
// up, what is refused) is tested without a GPU in tests/cpu/test_map_algebra.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <tuple>

#include "api/map_merge.h"
#include "core/map_format.h"
#include "core/mesh_analysis.h"
#include "core/voxel_color.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu_fixture.h"
#include "mesh_checks.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr size_t kFrames = 8;

gpu::GpuVolumeConfig config() {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.blockCapacity = 256;   // every part grows its pool; the merged map must hold the union
    return c;
}

// Every live block's step sums, counts and colour words, by coordinate (empty blocks too: the same frames
// allocate the same blocks, in one run or in parts).
using Corners = std::map<std::tuple<int, int, int>, std::tuple<std::vector<int32_t>, std::vector<float>, std::vector<uint32_t>>>;
Corners cornersOf(const gpu::GpuVolume& volume) {
    Corners out;
    for (auto& b : volume.downloadBlocks()) out[{b.coord.x(), b.coord.y(), b.coord.z()}] = {b.sdfSum, b.weight, b.color};
    return out;
}

// The mesh, order-free: triangles by vertex position, and per vertex (position bits) its normal bits and colour.
struct MeshState {
    std::vector<CanonicalTriangle> triangles;
    std::map<std::array<uint32_t, 3>, std::pair<std::array<uint32_t, 3>, uint32_t>> vertices;
    size_t borderEdges = 0;
};
size_t borderEdges(const std::vector<std::array<std::array<uint32_t, 3>, 3>>& triangles);
MeshState meshOf(gpu::GpuVolume& volume) {
    MeshState m;
    const gpu::ExportedMesh mesh = volume.exportMesh();
    m.triangles = canonicalTriangles(test::soupOf(mesh));
    for (const gpu::Vertex& v : mesh.vertices) {
        std::array<uint32_t, 3> p, n;
        std::memcpy(p.data(), &v.px, 12);
        std::memcpy(n.data(), &v.nx, 12);
        m.vertices[p] = {n, v.color};
    }
    std::vector<std::array<std::array<uint32_t, 3>, 3>> bits;
    for (const auto& t : mesh.triangles) {
        std::array<std::array<uint32_t, 3>, 3> b;
        for (int k = 0; k < 3; ++k) std::memcpy(b[k].data(), &mesh.vertices[t[k]].px, 12);
        bits.push_back(b);
    }
    m.borderEdges = borderEdges(bits);
    return m;
}

// The largest difference of two RGBA8 words' channels.
int largestColorDifference(uint32_t a, uint32_t b) {
    int d = 0;
    for (int shift = 0; shift < 32; shift += 8) d = std::max(d, std::abs(int((a >> shift) & 255) - int((b >> shift) & 255)));
    return d;
}

// A corner's colour word as RGBA8 (alpha 255 when it has one).
uint32_t cornerRgba(uint32_t word) {
    if (!hasVoxelColor(word)) return 0;
    const std::array<uint8_t, 3> c = voxelColor8(word);
    return uint32_t(c[0]) | uint32_t(c[1]) << 8 | uint32_t(c[2]) << 16 | 255u << 24;
}

void expectSameMap(const Corners& oneCorners, const MeshState& oneMesh, gpu::GpuVolume& merged, const std::string& what) {
    SCOPED_TRACE(what);
    const Corners corners = cornersOf(merged);
    ASSERT_EQ(corners.size(), oneCorners.size()) << "the same blocks";
    size_t differingTsdf = 0, colorWords = 0, colorOffByMore = 0;
    for (const auto& [coord, values] : oneCorners) {
        auto it = corners.find(coord);
        ASSERT_NE(it, corners.end()) << "a block of the one run is missing";
        differingTsdf += std::get<0>(values) != std::get<0>(it->second) ||
                         std::memcmp(std::get<1>(values).data(), std::get<1>(it->second).data(), std::get<1>(values).size() * 4) != 0;
        for (size_t c = 0; c < std::get<2>(values).size(); ++c) {
            const uint32_t a = std::get<2>(values)[c], b = std::get<2>(it->second)[c];
            colorWords += a != b;
            colorOffByMore += largestColorDifference(cornerRgba(a), cornerRgba(b)) > 1;
        }
    }
    EXPECT_EQ(differingTsdf, 0u) << "TSDF bits (step sums and counts)";
    EXPECT_EQ(colorOffByMore, 0u) << "corner colours within one 8-bit level (" << colorWords << " words differ at all)";

    const MeshState mesh = meshOf(merged);
    EXPECT_GT(oneMesh.triangles.size(), 3000u);
    EXPECT_EQ(mesh.triangles.size(), oneMesh.triangles.size());
    EXPECT_EQ(countTriangleMismatches(oneMesh.triangles, mesh.triangles, 0), 0u) << "the same triangles";
    ASSERT_EQ(mesh.vertices.size(), oneMesh.vertices.size());
    size_t normals = 0, colors = 0;
    for (const auto& [p, nc] : oneMesh.vertices) {
        auto it = mesh.vertices.find(p);
        ASSERT_NE(it, mesh.vertices.end()) << "a vertex position of the one run is missing";
        normals += it->second.first != nc.first;
        colors += largestColorDifference(it->second.second, nc.second) > 1;
    }
    EXPECT_EQ(normals, 0u) << "vertex normal bits";
    EXPECT_EQ(colors, 0u) << "vertex colours within one 8-bit level";
    const auto problems = test::checkInvariants(merged.downloadMeshState(), merged.config());
    EXPECT_TRUE(problems.empty()) << problems.front();
}

using PositionBits = std::array<uint32_t, 3>;
PositionBits bitsOf(const Eigen::Vector3f& p) {
    PositionBits b;
    std::memcpy(b.data(), p.data(), 12);
    return b;
}

// Edges used by exactly one triangle (the mesh's border: walls cut by the view), by the vertices' position bits.
size_t borderEdges(const std::vector<std::array<PositionBits, 3>>& triangles) {
    std::map<std::pair<PositionBits, PositionBits>, int> uses;
    for (const auto& t : triangles)
        for (int e = 0; e < 3; ++e) ++uses[std::minmax(t[e], t[(e + 1) % 3])];
    return size_t(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second == 1; }));
}

// The tiles joined by vertex position bits are the mesh of the sum: the same triangles, as many vertices (a vertex
// on a tile boundary is one vertex, in each tile that uses it, with its normal), and no edge of a tile boundary left
// open (as many border edges as the one run's mesh).
void expectTilesJoinToTheMesh(const std::vector<std::pair<TileKey, Mesh>>& tiles, const MergeReport& report, const MeshState& oneMesh) {
    ASSERT_GE(tiles.size(), 4u) << "the room spans several tiles";
    EXPECT_EQ(report.tiles, tiles.size());
    EXPECT_LT(report.tileBlocksMax, report.blocks) << "a tile with its neighbours is less than the whole map";
    std::vector<Eigen::Vector3f> soup;
    std::vector<std::array<PositionBits, 3>> joined;
    std::map<PositionBits, std::array<uint32_t, 3>> normals;
    std::map<PositionBits, int> tilesOf;   // how many tiles hold each vertex
    for (const auto& [key, m] : tiles) {
        for (size_t v = 0; v < m.positions.size(); ++v) {
            std::array<uint32_t, 3> n;
            std::memcpy(n.data(), m.normals[v].data(), 12);
            auto [it, fresh] = normals.emplace(bitsOf(m.positions[v]), n);
            EXPECT_TRUE(fresh || it->second == n) << "a boundary vertex has the same normal in every tile";
            ++tilesOf[bitsOf(m.positions[v])];
        }
        for (const auto& t : m.triangles) {
            joined.push_back({bitsOf(m.positions[t[0]]), bitsOf(m.positions[t[1]]), bitsOf(m.positions[t[2]])});
            for (uint32_t v : t) soup.push_back(m.positions[v]);
        }
    }
    EXPECT_GT(std::count_if(tilesOf.begin(), tilesOf.end(), [](const auto& t) { return t.second > 1; }), 100) << "tiles share boundary vertices";
    const std::vector<CanonicalTriangle> triangles = canonicalTriangles(soup);
    EXPECT_EQ(triangles.size(), oneMesh.triangles.size());
    EXPECT_EQ(countTriangleMismatches(oneMesh.triangles, triangles, 0), 0u) << "the tiles' triangles are the mesh's";
    EXPECT_EQ(normals.size(), oneMesh.vertices.size()) << "no vertex twice, none missing";
    size_t normalMismatches = 0;
    for (const auto& [p, n] : normals) {
        auto it = oneMesh.vertices.find(p);
        normalMismatches += it == oneMesh.vertices.end() || it->second.first != n;
    }
    EXPECT_EQ(normalMismatches, 0u) << "vertex positions and normals bit for bit";
    EXPECT_EQ(borderEdges(joined), oneMesh.borderEdges) << "no seam: no edge left open along a tile boundary";
}

class MapMergeTest : public GpuTest {
protected:
    std::filesystem::path dir_ = test::makeTempDir("map_merge");
};

// The one run, and the same frames split 2 and 7 ways (parts merged in a rotated order): each merge is
// the one run's map, loaded from its file. The 2-way merge is also meshed in tiles of 8 x 8 x 8 blocks.
TEST_F(MapMergeTest, SplitRunsAddUpToTheOneRunsMap) {
    gpu::GpuVolume one(context(), config());
    test::integrateNoisyRoomOrbit(one, 0, kFrames);
    one.exportMesh();   // cubes left pending at the last frame are meshed, as after the merge's rebuild
    const Corners oneCorners = cornersOf(one);
    const MeshState oneMesh = meshOf(one);

    for (size_t parts : {2u, 7u}) {
        std::vector<std::filesystem::path> inputs;
        for (size_t p = 0; p < parts; ++p) {
            gpu::GpuVolume part(context(), config());
            test::integrateNoisyRoomOrbit(part, p * kFrames / parts, (p + 1) * kFrames / parts);
            inputs.push_back(dir_ / ("part" + std::to_string(parts) + "_" + std::to_string(p) + ".vkmap"));
            part.save(inputs.back());
        }
        std::rotate(inputs.begin(), inputs.begin() + parts / 2, inputs.end());   // the order of the parts does not matter
        const std::filesystem::path out = dir_ / ("merged" + std::to_string(parts) + ".vkmap");
        MergeOptions options;
        std::vector<std::pair<TileKey, Mesh>> tiles;
        if (parts == 2) {   // and tile by tile: 8 x 8 x 8 blocks a tile (2.56 m)
            options.tileSize = 8 * gpu::BLOCK_SIDE * config().params.voxelSize;
            options.tileSink = [&](const TileKey& t, const Mesh& m) { tiles.emplace_back(t, m); };
        }
        const MergeReport report = mergeMaps(context(), inputs, out, options);
        if (parts == 2) expectTilesJoinToTheMesh(tiles, report, oneMesh);
        EXPECT_EQ(report.framesIntegrated, kFrames);
        EXPECT_EQ(report.blocks, oneCorners.size());
        EXPECT_GT(report.sharedBlocks, 0u);
        EXPECT_TRUE(report.frameStorePath.empty()) << "volumes saved without frames: no store";
        EXPECT_EQ(report.meshTriangles, oneMesh.triangles.size());
        std::unique_ptr<gpu::GpuVolume> merged = gpu::GpuVolume::load(context(), out);
        expectSameMap(oneCorners, oneMesh, *merged, std::to_string(parts) + " parts");
    }
}

}  // namespace
}  // namespace vkmesh
