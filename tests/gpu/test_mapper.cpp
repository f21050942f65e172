// The library's frame loop (api/mapper.h): what it does with each kind of frame (given, tracked, lost, without depth),
// what it hands to sinks, and what it counts (RunStats and its JSON, the keys `vkmesh fuse --stats` writes).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "api/mapper.h"
#include "api/run_stats_json.h"
#include "gpu_fixture.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

constexpr int kWidth = 160, kHeight = 120;

MapperOptions smallRoomOptions() {
    MapperOptions o;
    o.volume.params.voxelSize = 0.05f;
    o.volume.params.maxDepth = 6.0f;
    o.volume.blockCapacity = 4096;
    o.volume.vertexCapacity = 1u << 17;
    o.volume.chunkCapacity = 1u << 17;
    return o;
}

struct Frames {
    std::vector<DepthImage> depth;
    std::vector<Pose> poses;
    Intrinsics intrinsics = synth::kinectIntrinsics(kWidth, kHeight);
};

// The first `count` frames of a 120-frame orbit: a few centimetres apart, as tracking expects of consecutive frames.
Frames roomFrames(size_t count) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    Frames f;
    const std::vector<Pose> path = synth::cameraPath(120);
    f.poses.assign(path.begin(), path.begin() + long(count));
    for (const Pose& pose : f.poses) f.depth.push_back(scene.renderDepth(f.intrinsics, pose, {}));
    return f;
}

// Records every frame a sink is handed.
struct RecordingSink final : FrameSink {
    std::vector<uint32_t> frames;
    std::vector<FrameStatus> statuses;
    void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume&) override {
        frames.push_back(frame.index);
        statuses.push_back(result.status);
    }
};

bool hasWarning(const RunStats& s, const std::string& text) {
    return std::any_of(s.warnings.begin(), s.warnings.end(), [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

class MapperTest : public test::GpuTest {};

// Given poses: every frame with depth is fused, a frame without valid depth is skipped (counted, with a warning that
// names its source, not fused: the volume's frame count does not move), and every frame reaches the sinks once.
TEST_F(MapperTest, GivenFramesAreFusedAndAFrameWithoutDepthIsSkipped) {
    const Frames f = roomFrames(6);
    Mapper mapper(context(), smallRoomOptions());
    RecordingSink sink;
    mapper.addSink(&sink);
    const DepthImage empty{kWidth, kHeight, std::vector<float>(size_t(kWidth) * kHeight, 0.0f)};
    for (uint32_t i = 0; i < 6; ++i) {
        MapperFrame frame;
        frame.index = 10 + i;
        frame.timestamp = i;
        frame.depth = i == 3 ? &empty : &f.depth[i];
        frame.intrinsics = f.intrinsics;
        frame.pose = f.poses[i];
        frame.source = "frame" + std::to_string(i) + ".png";
        const MapperResult r = mapper.process(frame);
        EXPECT_EQ(r.status, i == 3 ? FrameStatus::Skipped : FrameStatus::Fused) << i;
        EXPECT_EQ(r.fused.has_value(), i != 3);
        EXPECT_TRUE(r.posed);
    }
    mapper.finish();
    EXPECT_EQ(mapper.volume().framesIntegrated(), 5u);
    const RunStats s = mapper.stats();
    EXPECT_EQ(s.integrated, 5u);
    EXPECT_EQ(s.skipped, 1u);
    EXPECT_TRUE(hasWarning(s, "frame 13 skipped: no valid depth in frame3.png"));
    EXPECT_EQ(s.frameWallMs.size(), 5u);
    EXPECT_EQ(s.perFrameCounts.at("touched_blocks").size(), 5u);
    EXPECT_FALSE(s.tracking.enabled);
    EXPECT_EQ(sink.frames, (std::vector<uint32_t>{10, 11, 12, 13, 14, 15}));
    ASSERT_EQ(mapper.trajectory().size(), 6u);
    EXPECT_EQ(mapper.trajectory()[3].index, 13u);
    EXPECT_TRUE(mapper.poses()[5].isApprox(f.poses[5]));

    const nlohmann::json j = runStatsJson(mapper);
    EXPECT_EQ(j["frames"]["integrated"], 5);
    EXPECT_EQ(j["frames"]["skipped"], 1);
    EXPECT_EQ(j["tracking"]["enabled"], false);
    EXPECT_EQ(j["loop_closure"]["enabled"], false);
    EXPECT_EQ(j["blocks"]["in_use"], mapper.volume().readCounters().blocksInUse);
    for (const char* key : {"gpu_ms_per_frame", "per_frame_counts", "wall_ms_per_frame", "capacity_events", "capacities", "heaps",
                            "gpu_pool_bytes", "warnings", "recycling", "color"})
        EXPECT_TRUE(j.contains(key)) << key;
}

// A tracked run starts at the first frame's start pose, tracks the next ones against the mesh, and keeps a frame it
// cannot track (no depth) out of the map: lost, at the predicted pose, not fused; tracking picks up again after it.
TEST_F(MapperTest, TrackedRunStartsAtItsStartPoseAndKeepsALostFrameOutOfTheMap) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // tracking draws the mesh
    const Frames f = roomFrames(8);
    MapperOptions options = smallRoomOptions();
    options.volume.publishMesh = true;
    options.tracker.maxDepth = 6.0f;
    Mapper mapper(context(), options);
    const DepthImage empty{kWidth, kHeight, std::vector<float>(size_t(kWidth) * kHeight, 0.0f)};
    uint32_t fusedBefore = 0;
    for (uint32_t i = 0; i < 8; ++i) {
        MapperFrame frame;
        frame.index = i;
        frame.depth = i == 5 ? &empty : &f.depth[i];
        frame.intrinsics = f.intrinsics;
        frame.startPose = f.poses[0];
        frame.reference = f.poses[i];
        if (i == 5) fusedBefore = mapper.volume().framesIntegrated();
        const MapperResult r = mapper.process(frame);
        ASSERT_TRUE(r.tracking.has_value()) << i;
        if (i == 0) {
            EXPECT_TRUE(r.cameraToWorld.isApprox(f.poses[0]));
        }
        if (i == 5) {
            EXPECT_EQ(r.status, FrameStatus::Lost);
            EXPECT_EQ(mapper.volume().framesIntegrated(), fusedBefore);
        } else {
            EXPECT_EQ(r.status, FrameStatus::Fused) << i << ": " << r.tracking->lostReason;
            EXPECT_LT((r.cameraToWorld.block<3, 1>(0, 3) - f.poses[i].block<3, 1>(0, 3)).norm(), 0.03) << i;
        }
    }
    mapper.finish();
    const RunStats s = mapper.stats();
    EXPECT_TRUE(s.tracking.enabled);
    EXPECT_EQ(s.integrated, 7u);
    EXPECT_EQ(s.tracking.lostFrames, 1u);
    ASSERT_EQ(s.tracking.lost.size(), 1u);
    EXPECT_EQ(s.tracking.lost[0].frame, 5u);
    EXPECT_EQ(s.tracking.ms.size(), 7u);              // every frame after the first went through tracking
    EXPECT_EQ(s.tracking.positionError.size(), 8u);   // every frame has a reference
    EXPECT_TRUE(hasWarning(s, "frame 5 lost (not fused)"));
    const nlohmann::json j = runStatsJson(mapper);
    EXPECT_EQ(j["tracking"]["frames_tracked"], 6);
    EXPECT_EQ(j["tracking"]["lost_frames"], 1);
}

}  // namespace
}  // namespace vkmesh
