// Maps that outlive the process (docs/MAPFILE.md): fusing N frames, saving, loading and fusing the rest gives
// exactly the state of one uninterrupted run (TSDF bits, the triangle set, vertex ages), on either hash path
// and into larger capacities; a map that cannot be loaded is an Error naming the file and the problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <tuple>

#include "api/reconstructor.h"
#include "core/map_format.h"
#include "core/mesh_analysis.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "map_state.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr int kWidth = 160, kHeight = 120;

// A small block pool, so that it grows before and after the save, and recycling, so that the free lists have
// holes and the hash has tombstones when it is saved.
gpu::GpuVolumeConfig resumeConfig(bool recycling) {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.blockCapacity = 512;   // grows (and defers a frame) before and after the save
    // The heaps stay roomy: a heap exhausted in the middle of a frame leaves cubes INCOMPLETE, and which ones
    // (so which vertices are created a frame later) depends on the order of the claims' atomics: two
    // uninterrupted runs then differ in some vertices' ages already.
    if (recycling) {
        c.keepRadius = 2.5f;
        c.recycle = true;
        c.recycleAfterFrames = 3;
        c.starveWeight = 64.0f;
    }
    return c;
}

using test::expectSameState;
using test::stateOf;

class ResumeTest : public GpuTest, public ::testing::WithParamInterface<bool /* recycling */> {};

TEST_P(ResumeTest, SaveLoadAndFuseTheRestIsTheUninterruptedRun) {
    const gpu::GpuVolumeConfig config = resumeConfig(GetParam());
    gpu::GpuVolume whole(context(), config);
    test::integrateNoisyRoomOrbit(whole, 0, 14);

    gpu::GpuVolume first(context(), config);
    test::integrateNoisyRoomOrbit(first, 0, 7);
    // Through the bytes of a file (the writer and the parser), into a new volume.
    const map::MapData saved = map::parse(map::serialize(first.saveMap()), "resume.vkmap");
    EXPECT_EQ(saved.blocks.size(), first.readCounters().blocksInUse);
    if (!GetParam()) {
        EXPECT_GT(saved.capacities.blocks, config.blockCapacity) << "the pool grew before the save";
    }
    EXPECT_FALSE(saved.vertexFree.holes.empty()) << "freed vertices below the high water";
    if (GetParam()) {
        EXPECT_FALSE(saved.blockFree.holes.empty()) << "recycled blocks";
    }
    std::unique_ptr<gpu::GpuVolume> resumed = gpu::GpuVolume::load(context(), saved, gpu::GpuVolume::mapConfig(saved), "resume.vkmap");
    EXPECT_EQ(resumed->frameNumber(), first.frameNumber());
    EXPECT_EQ(resumed->framesIntegrated(), 7u);
    EXPECT_EQ(resumed->readCounters().hashEntries, saved.blocks.size());
    // The loaded state is the saved one before any frame...
    auto problems = test::checkInvariants(resumed->downloadMeshState(), resumed->config());
    EXPECT_TRUE(problems.empty()) << problems.front();
    test::integrateNoisyRoomOrbit(*resumed, 7, 14);
    problems = test::checkInvariants(resumed->downloadMeshState(), resumed->config());
    EXPECT_TRUE(problems.empty()) << problems.front();
    // ... and after the rest of the frames it is the uninterrupted run's.
    expectSameState(stateOf(whole), stateOf(*resumed));
}
INSTANTIATE_TEST_SUITE_P(Map, ResumeTest, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? std::string("Recycling") : std::string("Plain"); });

// Saving changes nothing: a volume saved in the middle of its run ends as one that was not.
TEST_F(GpuTest, SavingChangesNothing) {
    const gpu::GpuVolumeConfig config = resumeConfig(false);
    gpu::GpuVolume a(context(), config), b(context(), config);
    test::integrateNoisyRoomOrbit(a, 0, 4);
    test::integrateNoisyRoomOrbit(b, 0, 4);
    (void)a.saveMap();
    test::integrateNoisyRoomOrbit(a, 4, 6);
    test::integrateNoisyRoomOrbit(b, 4, 6);

    expectSameState(stateOf(a), stateOf(b));
}

// The 32-bit hash path (VKMESH_PRETEND_MISSING), whose key words differ: the map holds coordinates, so it
// loads there, into larger capacities, and continues to the same TSDF and triangles.
std::unique_ptr<vk::Context> context32;
class Context32Teardown : public ::testing::Environment {
public:
    void TearDown() override { context32.reset(); }   // before static destruction (see test_block_hash.cpp)
};
const ::testing::Environment* const kTeardown = ::testing::AddGlobalTestEnvironment(new Context32Teardown);

vk::Context& contextWith32BitHash() {
    if (!context32) {
        const char* env = std::getenv("VKMESH_PRETEND_MISSING");
        const std::string saved = env ? env : "";
        setenv("VKMESH_PRETEND_MISSING", "shaderBufferInt64Atomics,shaderInt64", 1);
        context32 = std::make_unique<vk::Context>(vk::ContextOptions{-1, true});
        if (env) setenv("VKMESH_PRETEND_MISSING", saved.c_str(), 1);
        else unsetenv("VKMESH_PRETEND_MISSING");
    }
    return *context32;
}

TEST_F(GpuTest, MapLoadsOnThe32BitHashPathIntoLargerCapacities) {
    const gpu::GpuVolumeConfig config = resumeConfig(false);
    gpu::GpuVolume whole(context(), config);
    test::integrateNoisyRoomOrbit(whole, 0, 10);
    gpu::GpuVolume first(context(), config);
    test::integrateNoisyRoomOrbit(first, 0, 5);
    const map::MapData saved = map::parse(map::serialize(first.saveMap()), "cross.vkmap");

    vk::Context& other = contextWith32BitHash();
    other.takeValidationMessages();
    ASSERT_FALSE(other.int64Atomics());
    gpu::GpuVolumeConfig bigger = gpu::GpuVolume::mapConfig(saved);
    bigger.blockCapacity = 4 * saved.capacities.blocks;
    bigger.hashCapacity = 4 * saved.capacities.hashSlots;
    bigger.vertexCapacity = 2 * saved.capacities.vertices;
    bigger.chunkCapacity = 2 * saved.capacities.chunks;
    std::unique_ptr<gpu::GpuVolume> resumed = gpu::GpuVolume::load(other, saved, bigger, "cross.vkmap");
    EXPECT_EQ(resumed->config().blockCapacity, bigger.blockCapacity);
    EXPECT_EQ(resumed->config().hashCapacity, bigger.hashCapacity);
    EXPECT_EQ(resumed->readCounters().freeTop, bigger.blockCapacity - saved.blocks.size());
    test::integrateNoisyRoomOrbit(*resumed, 5, 10);
    // Other capacities grow at other times, and a frame that overflowed runs again under the next frame number,
    // so vertex ages may be offset; the TSDF and the triangles are the same.
    expectSameState(stateOf(whole), stateOf(*resumed), /*sameAges=*/false);
    // And back: saved on the 32-bit path, loaded on this one.
    const map::MapData back = map::parse(map::serialize(resumed->saveMap()), "back.vkmap");
    std::unique_ptr<gpu::GpuVolume> home = gpu::GpuVolume::load(context(), back, gpu::GpuVolume::mapConfig(back), "back.vkmap");
    expectSameState(stateOf(*resumed), stateOf(*home));
    auto messages = other.takeValidationMessages();
    EXPECT_TRUE(messages.empty()) << messages.front();
}

std::string loadError(vk::Context& context, const map::MapData& m, const gpu::GpuVolumeConfig& config) {
    try {
        gpu::GpuVolume::load(context, m, config, "bad.vkmap");
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST_F(GpuTest, MapsThatCannotBeLoadedAreClearErrors) {
    gpu::GpuVolume volume(context(), resumeConfig(false));
    test::integrateNoisyRoomOrbit(volume, 0, 2);
    const map::MapData good = volume.saveMap();
    const gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(good);

    gpu::GpuVolumeConfig otherVoxel = config;
    otherVoxel.params.voxelSize = 0.05f;
    std::string e = loadError(context(), good, otherVoxel);
    EXPECT_NE(e.find("bad.vkmap"), std::string::npos) << e;
    EXPECT_NE(e.find("voxel size"), std::string::npos) << e;
    EXPECT_NE(e.find("--voxel"), std::string::npos) << e;

    // A map keeps its allocation mode (de-integrating its frames repeats their allocation): a map allocated by
    // tiles says so in its config, and a config that would walk pixel by pixel is refused, naming the option. Maps
    // written before allocation by tiles hold 0 there: pixel by pixel.
    // Tiles are the default (since 2026-12-05), so a new map holds them and an old map's pixels must be asked for.
    EXPECT_TRUE(config.params.allocationTiles);
    map::MapData byPixels = good;
    byPixels.settings.allocationTiles = 0;
    const gpu::GpuVolumeConfig pixelConfig = gpu::GpuVolume::mapConfig(byPixels);
    EXPECT_FALSE(pixelConfig.params.allocationTiles);
    e = loadError(context(), byPixels, config);
    EXPECT_NE(e.find("allocation by tiles"), std::string::npos) << e;
    EXPECT_NE(e.find("--alloc-pixels"), std::string::npos) << e;
    map::MapData byTiles = good;
    byTiles.settings.allocationTiles = 1;
    EXPECT_TRUE(gpu::GpuVolume::mapConfig(byTiles).params.allocationTiles);
    e = loadError(context(), byTiles, pixelConfig);
    EXPECT_NE(e.find("allocation by tiles"), std::string::npos) << e;
    EXPECT_NE(e.find("--alloc-tiles"), std::string::npos) << e;
    // ... and the rules that decided its tiles: a map of the first rules (1: planes with g < 0 and tiles without
    // depth left to the pixels) keeps them, whatever the configuration asks for, and saves them again; a map of the
    // current rules (2) has those.
    gpu::GpuVolumeConfig tilesConfig = gpu::GpuVolume::mapConfig(byTiles);
    EXPECT_EQ(tilesConfig.params.allocationTileRules, int(gpu::ALLOC_TILE_RULES_FIRST));
    tilesConfig.params.allocationTileRules = int(gpu::ALLOC_TILE_RULES);
    const auto firstRules = gpu::GpuVolume::load(context(), byTiles, tilesConfig, "first.vkmap");
    EXPECT_EQ(firstRules->config().params.allocationTileRules, int(gpu::ALLOC_TILE_RULES_FIRST));
    EXPECT_EQ(firstRules->saveMap().settings.allocationTiles, gpu::ALLOC_TILE_RULES_FIRST);
    map::MapData currentRules = good;
    currentRules.settings.allocationTiles = gpu::ALLOC_TILE_RULES;
    EXPECT_EQ(gpu::GpuVolume::mapConfig(currentRules).params.allocationTileRules, int(gpu::ALLOC_TILE_RULES));

    map::MapData huge = good;   // capacities no device has
    huge.capacities.blocks = 1u << 30;
    e = loadError(context(), huge, gpu::GpuVolume::mapConfig(huge));
    EXPECT_NE(e.find("bad.vkmap"), std::string::npos) << e;
    EXPECT_NE(e.find("--blocks"), std::string::npos) << e;

    map::MapData noWeights = good;
    std::erase_if(noWeights.cornerArrays, [](const map::CornerArray& a) { return a.tag == map::tag("wght"); });
    e = loadError(context(), noWeights, config);
    EXPECT_NE(e.find("no section 'wght'"), std::string::npos) << e;

    map::MapData extra = good;
    extra.cornerArrays.push_back({map::tag("xtra"), std::vector<uint32_t>(good.blocks.size() * gpu::VOXELS_PER_BLOCK)});
    e = loadError(context(), extra, config);
    EXPECT_NE(e.find("'xtra' this build does not know"), std::string::npos) << e;

    // A map that fused colour must carry it.
    ASSERT_TRUE(good.features & map::FEATURE_COLOR);
    map::MapData noColor = good;
    std::erase_if(noColor.cornerArrays, [](const map::CornerArray& a) { return a.tag == map::tag("colr"); });
    e = loadError(context(), noColor, config);
    EXPECT_NE(e.find("no section 'colr'"), std::string::npos) << e;

    // Bad bytes never reach the GPU: GpuVolume::load(path) parses first.
    const auto dir = test::makeTempDir("map_errors");
    test::writeBytes(dir / "short.vkmap", map::serialize(good).substr(0, 100));
    try {
        gpu::GpuVolume::load(context(), dir / "short.vkmap");
        ADD_FAILURE() << "a truncated map loaded";
    } catch (const Error& err) {
        EXPECT_NE(std::string(err.what()).find("short.vkmap: truncated"), std::string::npos) << err.what();
    }
}

// The embedding API: Reconstructor::save / load forward to the volume; the published mesh is there at once.
TEST_F(GpuTest, ReconstructorSavesAndLoads) {
    ReconstructorOptions options;
    options.volume = resumeConfig(false);
    options.device = {-1, true};
    const auto dir = test::makeTempDir("map_reconstructor");
    const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const auto poses = synth::cameraPath(24, synth::PathKind::Orbit);
    Reconstructor rec(options);
    EXPECT_THROW(rec.save(dir / "empty.vkmap"), Error);
    for (int i = 0; i < 4; ++i) rec.integrate(scene.renderDepth(intr, poses[i], {}), intr, poses[i]);
    rec.save(dir / "rec.vkmap");
    std::unique_ptr<Reconstructor> loaded = Reconstructor::load(dir / "rec.vkmap", options);
    EXPECT_EQ(loaded->framesIntegrated(), 4u);
    EXPECT_EQ(loaded->meshBuffers().triangleCount, rec.meshBuffers().triangleCount);
    for (int i = 4; i < 6; ++i) {
        rec.integrate(scene.renderDepth(intr, poses[i], {}), intr, poses[i]);
        loaded->integrate(scene.renderDepth(intr, poses[i], {}), intr, poses[i]);
    }
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(test::soupOf(rec.downloadMesh())),
                                      canonicalTriangles(test::soupOf(loaded->downloadMesh())), 0),
              0u);
    EXPECT_EQ(loaded->context().validationMessageCount(), 0u);
    EXPECT_EQ(rec.context().validationMessageCount(), 0u);
}

}  // namespace
}  // namespace vkmesh
