// Map algebra on a GPU volume (docs/SCALING.md): the frames of one run split into parts, each part fused into a
// map of its own, and the maps merged (mergeMaps), give the map of the one run: TSDF bits (sums, counts), the
// triangle set, vertex position and normal bits, and colour within one 8-bit level. Meshed tile by tile, each tile
// alone on the GPU, the tiles joined are that mesh: no seam, no vertex twice. The host side (what adds
// up, what is refused) is tested without a GPU in tests/cpu/test_map_algebra.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
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

// ---- tiles made on their own: from the blocks each needs, read from the parts' files --------------------------

// A tile's mesh, order-free: each triangle as its vertices' position bits (rotated to start at the smallest, which
// keeps its winding), sorted; each vertex's normal bits by position bits.
struct TileState {
    std::vector<std::array<PositionBits, 3>> triangles;
    std::map<PositionBits, std::array<uint32_t, 3>> normals;
};
TileState tileStateOf(const Mesh& m) {
    TileState s;
    for (const auto& t : m.triangles) {
        std::array<PositionBits, 3> b = {bitsOf(m.positions[t[0]]), bitsOf(m.positions[t[1]]), bitsOf(m.positions[t[2]])};
        std::rotate(b.begin(), std::min_element(b.begin(), b.end()), b.end());
        s.triangles.push_back(b);
    }
    std::sort(s.triangles.begin(), s.triangles.end());
    for (size_t v = 0; v < m.positions.size(); ++v) {
        std::array<uint32_t, 3> n;
        std::memcpy(n.data(), m.normals[v].data(), 12);
        s.normals[bitsOf(m.positions[v])] = n;
    }
    return s;
}

std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

// The whole mesh cut into tiles as the tiles are defined (docs/SCALING.md, "Tiles"): a triangle belongs to the block
// holding its centroid (taken in the order of its vertices' position bits), a block to the tile holding its origin.
std::map<TileKey, TileState> cutIntoTiles(const Mesh& mesh, float voxel, double tileSize) {
    std::map<TileKey, Mesh> tiles;
    for (const auto& t : mesh.triangles) {
        std::array<Eigen::Vector3f, 3> p = {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
        std::sort(p.begin(), p.end(), [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return std::memcmp(a.data(), b.data(), 12) < 0; });
        const Eigen::Vector3f c = (p[0] + p[1] + p[2]) / 3.0f;
        TileKey key;
        for (int a = 0; a < 3; ++a) {
            const int32_t block = int32_t(std::floor(std::floor(c[a] / voxel) / float(gpu::BLOCK_SIDE)));
            key[a] = int32_t(std::floor(double(block) * double(voxel) * gpu::BLOCK_SIDE / tileSize));
        }
        Mesh& tile = tiles[key];
        for (uint32_t v : t) tile.positions.push_back(mesh.positions[v]), tile.normals.push_back(mesh.normals[v]);
        const uint32_t n = uint32_t(tile.positions.size());
        tile.triangles.push_back({n - 3, n - 2, n - 1});
    }
    std::map<TileKey, TileState> out;
    for (const auto& [key, tile] : tiles) out[key] = tileStateOf(tile);
    return out;
}

// Each tile made alone by mergeTiles, reading only its blocks (and one around them) from the parts' files, is that
// tile of the whole sum's mesh: the same triangles, vertex position and normal bits; and no tile needed the whole map.
TEST_F(MapMergeTest, TileMadeAloneFromItsBlocksEqualsTheTileOfTheWholeSum) {
    std::vector<std::filesystem::path> inputs;
    size_t inputBlocks = 0;
    for (size_t p = 0; p < 2; ++p) {
        gpu::GpuVolume part(context(), config());
        test::integrateNoisyRoomOrbit(part, p * kFrames / 2, (p + 1) * kFrames / 2);
        inputs.push_back(dir_ / ("tile_part" + std::to_string(p) + ".vkmap"));
        part.save(inputs.back());
        inputBlocks += map::readFile(inputs.back()).blocks.size();
    }
    const float voxel = config().params.voxelSize;
    const double size = 8 * gpu::BLOCK_SIDE * voxel;   // 2.56 m

    MergeOptions whole;
    whole.returnMesh = true;
    const MergeReport sum = mergeMaps(context(), inputs, dir_ / "tile_sum.vkmap", whole);
    const std::map<TileKey, TileState> expected = cutIntoTiles(sum.mesh, voxel, size);
    ASSERT_GE(expected.size(), 4u) << "the room spans several tiles";

    const TilePlan plan = planTiles(inputs, size);
    EXPECT_EQ(plan.blocks, sum.blocks) << "the sum's blocks, counted from the block tables alone";
    for (const auto& [key, tile] : expected)
        EXPECT_TRUE(std::binary_search(plan.tiles.begin(), plan.tiles.end(), key)) << "every tile with a triangle is listed";

    // The 4 tiles with the most triangles (they meet along tile boundaries; each tile costs a GPU volume of its own,
    // and the whole tiling is MapMergeTest.SplitRunsAddUpToTheOneRunsMap's), in one call: one worker's share, each tile
    // read, added and meshed alone, one after the other.
    std::vector<TileKey> asked;
    for (const auto& [key, tile] : expected) asked.push_back(key);
    std::sort(asked.begin(), asked.end(), [&](const TileKey& a, const TileKey& b) {
        return expected.at(a).triangles.size() > expected.at(b).triangles.size();
    });
    asked.resize(4);
    std::map<TileKey, Mesh> alone;
    TileOptions options;
    options.tileSize = size;
    options.tileSink = [&](const TileKey& t, const Mesh& m) { alone[t] = m; };
    const TilesReport report = mergeTiles(context(), inputs, asked, options);
    ASSERT_EQ(report.tiles.size(), asked.size());
    EXPECT_EQ(report.tableBlocks, inputBlocks);
    EXPECT_LT(report.gpuBlocksMax, plan.blocks) << "no tile needed the whole map on the GPU";
    EXPECT_LT(report.hostBlocksMax, inputBlocks + plan.blocks) << "nor what adding the whole maps holds in memory";
    EXPECT_EQ(alone.size(), asked.size());
    for (const TileReport& r : report.tiles) {
        SCOPED_TRACE("tile " + tileFileName(r.tile));
        EXPECT_GT(r.blocksMeshed, 0u) << "a listed tile holds blocks of the sum";
        EXPECT_LT(r.blocksRead, inputBlocks) << "only the blocks the tile needs are read";
        EXPECT_LE(r.blocksMeshed, report.gpuBlocksMax);
        const auto want = expected.find(r.tile);
        ASSERT_TRUE(alone.count(r.tile));
        const TileState got = tileStateOf(alone[r.tile]);
        EXPECT_EQ(r.triangles, want->second.triangles.size());
        EXPECT_EQ(alone[r.tile].positions.size(), want->second.normals.size()) << "as many vertices, none twice";
        EXPECT_TRUE(got.triangles == want->second.triangles) << "the same triangles, by vertex position bits";
        EXPECT_TRUE(got.normals == want->second.normals) << "the same vertex positions and normal bits";
    }

    // Bad input names the file or the value.
    std::string e = errorOf([&] { mergeTiles(context(), {inputs[0], dir_ / "missing.vkmap"}, plan.tiles, options); });
    EXPECT_NE(e.find("missing.vkmap"), std::string::npos) << e;
    e = errorOf([&] { planTiles(inputs, 0); });
    EXPECT_NE(e.find("tile size 0"), std::string::npos) << e;
    // A tile far from the map holds no block: nothing is read or meshed.
    const TilesReport far = mergeTiles(context(), inputs, {TileKey{1000, 0, 0}}, options);
    EXPECT_EQ(far.tiles[0].blocksRead + far.tiles[0].blocksMeshed + far.tiles[0].triangles, 0u);
}

// map::BlockReader returns exactly the blocks in a box, their TSDF records as stored, the mesh's arrays empty; a bad
// box or file is an error naming the file.
TEST_F(MapMergeTest, BlockReaderReadsExactlyTheBlocksInABox) {
    const std::filesystem::path file = dir_ / "reader.vkmap";
    {
        gpu::GpuVolume volume(context(), config());
        test::integrateNoisyRoomOrbit(volume, 0, 3);
        volume.save(file);
    }
    const map::MapData whole = map::readFile(file);
    map::BlockReader reader(file);
    ASSERT_EQ(reader.blocks().size(), whole.blocks.size());
    std::array<int32_t, 3> lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
    for (size_t i = 0; i < whole.blocks.size(); ++i) {
        const map::Block& b = whole.blocks[i];
        const auto& e = reader.blocks()[i];
        EXPECT_TRUE(e.x == b.x && e.y == b.y && e.z == b.z && e.hashStamp == b.hashStamp) << "block table entry " << i;
        const std::array<int32_t, 3> c{b.x, b.y, b.z};
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
    }
    map::BlockBox box;
    for (int a = 0; a < 3; ++a) box.lo[a] = lo[a] + (hi[a] - lo[a]) / 4, box.hi[a] = hi[a] - (hi[a] - lo[a]) / 4;
    const map::MapData part = reader.read(box);

    std::vector<size_t> inBox;
    for (size_t i = 0; i < whole.blocks.size(); ++i)
        if (box.contains(whole.blocks[i].x, whole.blocks[i].y, whole.blocks[i].z)) inBox.push_back(i);
    ASSERT_GT(inBox.size(), 0u);
    ASSERT_LT(inBox.size(), whole.blocks.size());
    ASSERT_EQ(part.blocks.size(), inBox.size()) << "the blocks in the box, no other";
    EXPECT_EQ(part.frameNumber, whole.frameNumber);
    EXPECT_EQ(part.saveId, whole.saveId);
    EXPECT_EQ(std::memcmp(&part.settings, &whole.settings, sizeof(map::Settings)), 0);
    ASSERT_EQ(part.cornerArrays.size(), whole.cornerArrays.size());
    size_t differing = 0, meshWords = 0;
    for (size_t k = 0; k < inBox.size(); ++k) {
        const map::Block& want = whole.blocks[inBox[k]];
        const map::Block& got = part.blocks[k];
        EXPECT_TRUE(got.x == want.x && got.y == want.y && got.z == want.z && got.index == k);
        for (const map::CornerArray& a : whole.cornerArrays) {
            const map::CornerArray* read = part.corners(a.tag);
            ASSERT_NE(read, nullptr) << map::tagName(a.tag);
            const uint32_t* g = read->words.data() + k * gpu::VOXELS_PER_BLOCK;
            const uint32_t* w = a.words.data() + inBox[k] * gpu::VOXELS_PER_BLOCK;
            if (a.tag == map::tag("sdf_") || a.tag == map::tag("wght") || a.tag == map::tag("colr")) {
                differing += std::memcmp(g, w, 4 * gpu::VOXELS_PER_BLOCK) != 0;
            } else {   // the mesh's: empty, rebuilt from the TSDF
                const uint32_t empty = a.tag == map::tag("cube") ? 0u : gpu::EMPTY_SLOT;
                meshWords += size_t(std::count_if(g, g + gpu::VOXELS_PER_BLOCK, [&](uint32_t v) { return v != empty; }));
            }
        }
    }
    EXPECT_EQ(differing, 0u) << "each block's TSDF records as stored";
    EXPECT_EQ(meshWords, 0u) << "no mesh is read";
    EXPECT_TRUE(part.vertices.empty() && part.chunkWords.empty());
    EXPECT_NO_THROW(reader.verifyChecksum());
    // The whole box is the whole map, and a box beside the map is empty.
    EXPECT_EQ(reader.read(map::BlockBox{lo, hi}).blocks.size(), whole.blocks.size());
    EXPECT_EQ(reader.read(map::BlockBox{{hi[0] + 1, lo[1], lo[2]}, {hi[0] + 5, hi[1], hi[2]}}).blocks.size(), 0u);

    auto expectError = [&](const std::function<void()>& f, const std::filesystem::path& name, const std::string& what) {
        const std::string e = errorOf(f);
        EXPECT_NE(e.find(name.string()), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
    };
    expectError([&] { reader.read(map::BlockBox{{0, 5, 0}, {0, 4, 0}}); }, file, "block box (0, 5, 0) to (0, 4, 0) is empty");
    expectError([&] { reader.read(map::BlockBox{{0, 0, -(1 << 20) - 1}, {0, 0, 0}}); }, file, "reaches outside");
    expectError([&] { map::BlockReader(dir_ / "missing.vkmap"); }, dir_ / "missing.vkmap", "cannot open map file");

    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    auto written = [&](const std::string& name, const std::string& content) {
        const std::filesystem::path path = dir_ / name;
        std::ofstream(path, std::ios::binary) << content;
        return path;
    };
    const std::filesystem::path truncated = written("truncated.vkmap", bytes.substr(0, bytes.size() / 2));
    expectError([&] { map::BlockReader{truncated}; }, truncated, "truncated");
    const std::filesystem::path text = written("text.vkmap", "solid mesh\n");
    expectError([&] { map::BlockReader{text}; }, text, "not a vkmesh map");
    // A flipped bit in a TSDF record: the block reader seeks past what it does not read, so the sections' checksum is
    // verifyChecksum()'s (map::readFile checks it always).
    const size_t firstSdfRecord = map::kHeaderBytes + 4 * map::kSectionHeaderBytes + 96 + 24 + sizeof(gpu::Counters) + sizeof(gpu::FramePush) +
                                  map::kSectionHeaderBytes + whole.blocks.size() * map::kBlockRecordBytes + map::kSectionHeaderBytes;
    ASSERT_EQ(map::tagName(*reinterpret_cast<const uint32_t*>(bytes.data() + firstSdfRecord - map::kSectionHeaderBytes)), "sdf_");
    std::string flipped = bytes;
    flipped[firstSdfRecord + 100] ^= 0x04;
    const std::filesystem::path corrupt = written("corrupt.vkmap", flipped);
    map::BlockReader corruptReader(corrupt);
    expectError([&] { corruptReader.verifyChecksum(); }, corrupt, "checksum mismatch");
    expectError([&] { map::readFile(corrupt); }, corrupt, "checksum mismatch");
}

}  // namespace
}  // namespace vkmesh
