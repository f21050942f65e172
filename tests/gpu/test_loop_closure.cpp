// Loop closure and relocalisation (docs/LOOP_CLOSURE.md): the random ferns, the pose graph, the registration that
// verifies a loop, and `vkmesh fuse --track --loop-closure` end to end on synthetic sequences with exact ground
// truth (drift around a loop, kidnapping, a false loop, determinism).
#include <gtest/gtest.h>

#include <zstd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "core/camera.h"
#include "core/icp_solve.h"
#include "core/map_format.h"
#include "io/dataset.h"
#include "io/text_lines.h"
#include "io/trajectory.h"
#include "slam/feature_relocaliser.h"
#include "slam/frame_registration.h"
#include "slam/loop_closer.h"
#include "slam/pose_graph.h"
#include "slam/random_ferns.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "test_support.h"

namespace vkmesh {
namespace {

namespace fs = std::filesystem;

Pose turned(const Pose& pose, double degrees, const Eigen::Vector3d& axis, const Eigen::Vector3d& moved) {
    Pose delta = Pose::Identity();
    delta.block<3, 3>(0, 0) = Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix();
    delta.block<3, 1>(0, 3) = moved;
    return pose * delta;
}

double angleDegrees(const Pose& a, const Pose& b) { return rotationDegrees(inverseRigid(a) * b); }
double distanceMetres(const Pose& a, const Pose& b) { return (a.block<3, 1>(0, 3) - b.block<3, 1>(0, 3)).norm(); }

// The same view gives the same code; a view a few centimetres away differs in few ferns, a view of another part
// of the room in many; and the ferns are the same for the same seed (deterministic), others for another seed.
TEST(RandomFerns, CodesTellNearbyViewsFromOtherPlaces) {
    const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const Intrinsics k = synth::kinectIntrinsics(160, 120);
    const std::vector<Pose> path = synth::cameraPath(40);
    ColorImage c0, cNear, cFar;
    const DepthImage d0 = room.renderDepth(k, path[0], {}, &c0);
    const DepthImage dNear = room.renderDepth(k, turned(path[0], 1.0, {0, 1, 0}, {0.02, 0, 0}), {}, &cNear);
    const DepthImage dFar = room.renderDepth(k, path[20], {}, &cFar);
    const slam::RandomFerns ferns;
    const slam::FernCode a = ferns.encode(ferns.shrink(d0, &c0));
    EXPECT_EQ(a.size(), 500u);
    EXPECT_EQ(a, slam::RandomFerns().encode(slam::RandomFerns().shrink(d0, &c0)));
    EXPECT_EQ(slam::RandomFerns::dissimilarity(a, a), 0.0);
    const double near = slam::RandomFerns::dissimilarity(a, ferns.encode(ferns.shrink(dNear, &cNear)));
    const double far = slam::RandomFerns::dissimilarity(a, ferns.encode(ferns.shrink(dFar, &cFar)));
    EXPECT_LT(near, 0.25);
    EXPECT_GT(far, 0.4);
    EXPECT_GT(far, 2 * near);
    slam::FernOptions other;
    other.seed = 2;
    EXPECT_NE(a, slam::RandomFerns(other).encode(slam::RandomFerns(other).shrink(d0, &c0)));
    // Depth only: the code still tells the places apart.
    const double farDepthOnly = slam::RandomFerns::dissimilarity(ferns.encode(ferns.shrink(d0, nullptr)), ferns.encode(ferns.shrink(dFar, nullptr)));
    EXPECT_GT(farDepthOnly, 0.1);
    EXPECT_NE(test::errorMessageOf([&] { ferns.shrink(synth::SyntheticScene::defaultRoom().renderDepth(synth::kinectIntrinsics(40, 30), path[0]), nullptr); })
                  .find("cannot shrink"),
              std::string::npos);
}

// The tracker's ICP against a keyframe's depth recovers a known offset between two views of the room.
TEST(FrameRegistration, RecoversAKnownOffsetBetweenTwoViews) {
    const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const Intrinsics k = synth::kinectIntrinsics(320, 240);
    const Pose keyPose = synth::cameraPath(40)[3];
    const Pose truth = turned(keyPose, 3.0, {0.3, 1, 0.2}, {0.04, -0.02, 0.03});
    synth::RenderOptions noisy;
    noisy.noise = true;
    const gpu::TrackerOptions tracker;
    const slam::RegistrationFrame key = slam::registrationFrame(room.renderDepth(k, keyPose, noisy), k, tracker);
    noisy.seed = 7;
    const slam::RegistrationFrame frame = slam::registrationFrame(room.renderDepth(k, truth, noisy), k, tracker);
    ASSERT_EQ(key.levels.front().width, 160);
    const slam::Registration r = slam::registerFrame(frame, key, keyPose, keyPose, tracker);
    ASSERT_TRUE(r.solved);
    const Pose error = inverseRigid(truth) * r.cameraToWorld;
    EXPECT_LT(translationMetres(error), 0.005);
    EXPECT_LT(rotationDegrees(error), 0.3);
    EXPECT_GT(r.inlierShare(), 0.5);
}

// A square loop whose odometry drifted: the loop edge closes it, the first node stays, and the drift is spread
// along the chain (each node moves towards the truth). A loop edge that contradicts everything (a false loop) is
// held by its Huber loss to a bounded pull.
TEST(PoseGraph, ALoopEdgeSpreadsTheDriftAlongTheChain) {
    std::vector<Pose> truth;
    for (int i = 0; i < 12; ++i) {
        Pose p = Pose::Identity();
        const double a = 2 * std::numbers::pi * i / 12;
        p.block<3, 3>(0, 0) = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        p.block<3, 1>(0, 3) = Eigen::Vector3d(std::cos(a), std::sin(a), 0);
        truth.push_back(p);
    }
    // Odometry with a small bias per step: the chain drifts.
    Pose bias = Pose::Identity();
    bias.block<3, 3>(0, 0) = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    bias(0, 3) = 0.009;
    slam::PoseGraph graph;
    std::vector<Pose> drifted{truth[0]};
    for (int i = 1; i < 12; ++i) drifted.push_back(drifted.back() * inverseRigid(truth[size_t(i - 1)]) * truth[size_t(i)] * bias);
    for (const Pose& p : drifted) graph.addNode(p);
    const slam::Information odometry = slam::diagonalInformation(0.01, 0.005);
    for (int i = 1; i < 12; ++i) graph.addEdge({i - 1, i, inverseRigid(drifted[size_t(i - 1)]) * drifted[size_t(i)], odometry, false});
    double before = 0;
    for (int i = 0; i < 12; ++i) before += translationMetres(inverseRigid(truth[size_t(i)]) * drifted[size_t(i)]);
    ASSERT_GT(translationMetres(inverseRigid(truth[11]) * drifted[11]), 0.05);
    // The loop: node 11 seen from node 0, exactly.
    const int loop = graph.addEdge({0, 11, inverseRigid(truth[0]) * truth[11], slam::diagonalInformation(0.005, 0.002), true});
    const slam::PoseGraphSolve solve = graph.optimise(50, 3.0);
    EXPECT_TRUE(solve.converged);
    EXPECT_LT(solve.finalCost, solve.initialCost);
    EXPECT_TRUE(graph.pose(0).isApprox(truth[0], 1e-12));
    double after = 0;
    for (int i = 0; i < 12; ++i) after += translationMetres(inverseRigid(truth[size_t(i)]) * graph.pose(i));
    EXPECT_LT(after, 0.5 * before);
    EXPECT_LT(graph.whitenedError(size_t(loop)), 3.0);
    // Deterministic: the same graph again gives the same poses bit for bit.
    slam::PoseGraph again;
    for (const Pose& p : drifted) again.addNode(p);
    for (const auto& e : graph.edges()) again.addEdge(e);
    again.optimise(50, 3.0);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(again.pose(i), graph.pose(i)) << i;
    EXPECT_NE(test::errorMessageOf([&] { graph.addEdge({0, 12, Pose::Identity(), odometry, false}); }).find("node"), std::string::npos);
}

// The loop closer on its own (no GPU): a lap of the room whose poses drift as a tracker's do (a world-frame error
// growing along the path to `driftMetres` sideways, a third of it forward, and 2 degrees by the lap's end), then the
// start again. The poses given after a correction go on from the corrected one, as the tracker's do
// (PoseTracker::correctLastPose). Returns the closer and what the tests below check.
struct DriftedLap {
    slam::LoopClosureStats stats;
    uint32_t closedAt = 0;          // the frame whose loop first corrected poses (0: none)
    size_t corrected = 0;           // poses handed back
    double before = 0, after = 0;   // the mean error of the lap's second half, as given and after the corrections
    double lastError = 0;           // frame 51's error after the corrections
    int olderMapFrames = 0;         // frames registered against the older map
};

// `olderMapFitAtTracked` > 0: each frame the closer asks for (wantsOlderMap) comes with a registration against the
// older map that puts it at its true pose (the older map is the lap's start, where the drift was still small) with
// an RMSE of 4 mm there and this RMSE at the given pose.
DriftedLap closeDriftedLap(const slam::LoopClosureOptions& options, double driftMetres, double olderMapFitAtTracked = 0) {
    const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const Intrinsics k = synth::kinectIntrinsics(160, 120);
    const std::vector<Pose> path = synth::cameraPath(120, synth::PathKind::Revisit);   // 3 laps of 40 frames
    slam::LoopCloser closer(options);
    std::vector<Pose> given;
    Pose followed = Pose::Identity();   // the corrections so far, as the tracker takes them on
    DriftedLap lap;
    for (uint32_t i = 0; i < 52; ++i) {
        const double s = double(i) / 40.0;
        const Pose drift = turned(Pose::Identity(), 2.0 * s, {0, 0, 1}, {driftMetres * s, driftMetres / 3 * s, 0.0});
        given.push_back(followed * drift * path[i]);
        synth::RenderOptions noisy;
        noisy.noise = true;
        noisy.seed = i + 1;
        ColorImage color;
        const DepthImage depth = room.renderDepth(k, path[i], noisy, &color);
        OlderMapRegistration older;
        older.tracked = true;
        older.cameraToWorld = path[i];
        older.rmse = 0.004;
        older.rmseAtTracked = olderMapFitAtTracked;
        const bool withOlder = olderMapFitAtTracked > 0 && closer.wantsOlderMap(i, given[i]);
        if (withOlder) ++lap.olderMapFrames;
        const PoseCorrections c = closer.frameFused({i, &depth, &color, k, given[i], withOlder ? &older : nullptr});
        if (c.empty()) continue;
        EXPECT_TRUE(std::is_sorted(c.frames.begin(), c.frames.end()));
        lap.corrected += c.frames.size();
        if (lap.closedAt == 0) lap.closedAt = i;
        Pose latest;
        EXPECT_TRUE(closer.latestPose(i, latest));
        followed = latest * inverseRigid(drift * path[i]);
    }
    lap.stats = closer.stats();
    int counted = 0;
    for (uint32_t i = 20; i < 40; ++i) {
        Pose latest;
        EXPECT_TRUE(closer.latestPose(i, latest)) << i;
        lap.before += distanceMetres(given[i], path[i]);
        lap.after += distanceMetres(latest, path[i]);
        ++counted;
    }
    lap.before /= counted, lap.after /= counted;
    Pose last;
    EXPECT_TRUE(closer.latestPose(51, last));
    lap.lastError = distanceMetres(last, path[51]);
    Pose unknown;
    EXPECT_FALSE(closer.latestPose(1000, unknown));
    return lap;
}

// 8 cm of drift: the revisit is recognised by the ferns, verified against the first keyframes' depth, and the
// graph's corrections move the drifted frames back towards the truth.
TEST(LoopCloser, ClosesALoopOverDriftedPosesAndCorrectsTheFrames) {
    slam::LoopClosureOptions options;
    options.registrationWidth = 160;
    const DriftedLap lap = closeDriftedLap(options, 0.08);
    ASSERT_GE(lap.stats.loopsAccepted, 1u) << "no loop closed (detected " << lap.stats.loopsDetected << ", rejected " << lap.stats.loopsRejected << ")";
    EXPECT_GE(lap.closedAt, 38u);
    EXPECT_GT(lap.corrected, 20u);
    // The frames of the lap's second half were furthest off; the corrections bring them back.
    EXPECT_LT(lap.after, 0.5 * lap.before) << "mean error " << lap.before << " -> " << lap.after << " m";
    // The frame that closed the loop, and those after it, are where the truth is, within the drift that goes on.
    EXPECT_LT(lap.lastError, 0.03);
}

// The same lap with the ferns proposing nothing (as on real data, where the revisits differ in more of their ferns
// than the threshold allows) and 15 cm of drift: the keyframes the graph puts near the camera are proposed by place,
// verified, and close the loop (past the 10 cm a loop proposed by place needs). Without candidates by place, nothing
// closes.
TEST(LoopCloser, ARevisitTheFernsMissIsProposedByPlace) {
    slam::LoopClosureOptions options;
    options.registrationWidth = 160;
    options.loopDissimilarity = -1;   // no code is that alike
    const DriftedLap lap = closeDriftedLap(options, 0.15);
    ASSERT_GE(lap.stats.loopsAccepted, 1u) << "no loop closed (detected " << lap.stats.loopsDetected << ", rejected " << lap.stats.loopsRejected << ")";
    for (const auto& loop : lap.stats.loops) EXPECT_EQ(loop.proposedBy, "proximity") << "frame " << loop.frame;
    EXPECT_LT(lap.after, 0.5 * lap.before) << "mean error " << lap.before << " -> " << lap.after << " m";
    EXPECT_LT(lap.lastError, 0.05);

    options.proximityCandidates = 0;
    const DriftedLap none = closeDriftedLap(options, 0.15);
    EXPECT_EQ(none.stats.loopsDetected, 0u);
    EXPECT_EQ(none.corrected, 0u);
}

// The same lap with neither ferns nor place proposing anything, and 6 cm of drift: the revisit's frames registered
// against the older map close the loop when that map fits them better at the matched pose (20 -> 4 mm), and the
// frames are corrected. A match that fits no better (4.2 -> 4 mm: it slid along what the geometry leaves free)
// moves nothing. The lap's first frames are not checked (no keyframe is old enough for a loop, none looks the same way).
TEST(LoopCloser, ARevisitMatchedToTheOlderMapClosesTheLoopOnlyWhenItFitsBetter) {
    slam::LoopClosureOptions options;
    options.registrationWidth = 160;
    options.loopDissimilarity = -1;
    options.proximityCandidates = 0;
    const DriftedLap lap = closeDriftedLap(options, 0.06, 0.020);
    ASSERT_GE(lap.stats.loopsAccepted, 1u) << "no loop closed (" << lap.olderMapFrames << " frames against the older map)";
    for (const auto& loop : lap.stats.loops) EXPECT_EQ(loop.proposedBy, "older map") << "frame " << loop.frame;
    EXPECT_GE(lap.closedAt, 30u) << "the lap's last quarter comes back towards its start";
    EXPECT_EQ(lap.stats.olderMapChecks, uint32_t(lap.olderMapFrames));
    EXPECT_LT(lap.olderMapFrames, 20) << "asked at frames that see nothing an old keyframe saw";
    EXPECT_LT(lap.after, 0.5 * lap.before) << "mean error " << lap.before << " -> " << lap.after << " m";
    EXPECT_LT(lap.lastError, 0.02);

    const DriftedLap noGain = closeDriftedLap(options, 0.06, 0.0042);
    EXPECT_GE(noGain.olderMapFrames, 1);
    EXPECT_GE(noGain.stats.olderMapMatches, 1u);
    EXPECT_EQ(noGain.stats.loopsDetected, 0u) << "a match that shows no drift is not a loop";
    EXPECT_EQ(noGain.corrected, 0u);
}

}  // namespace
}  // namespace vkmesh

namespace vkmesh {
namespace {

// The noisy room's revisit path (three laps of 60 frames at 320 x 240), rendered once for the tests below (and shared
// with their other programs), with frames cut out of laps 2 and 3 so that the camera jumps 10 times to places lap 1
// saw: frames 0-55, then 4 frames of every 12 from frame 60 on (each kept run starts with a jump of 5 or 8 frames:
// 30-48 degrees).
const fs::path& kidnapSequence() {
    static const fs::path dir = test::sharedSynthSequence("loop_kidnap", "--frames 180 --path revisit --noise --width 320 --height 240 --gt-spacing 0.05",
                                                          [](const fs::path& d) {
        std::ifstream in(d / "depth.txt");
        std::string line, kept;
        int frame = 0;
        while (std::getline(in, line)) {
            if (line.empty() || line[0] == '#') {
                kept += line + "\n";
                continue;
            }
            if (frame < 56 || (frame >= 60 && (frame - 60) % 12 < 4)) kept += line + "\n";
            ++frame;
        }
        in.close();
        std::ofstream(d / "depth.txt") << kept;
    });
    return dir;
}

// Kidnapping: after each of the 10 jumps the camera is relocalised within 5 frames, within 5 cm and 5 degrees of
// the truth, in at least 9 of the 10 (the relocalised frame and the next one tentative, the one after fused); no
// frame stays lost for good, and the map holds only tracked frames. And a second run of the first 60 frames gives
// the same decisions and online trajectory for them (determinism, below).
TEST(LoopClosure, KidnappedCameraIsRelocalisedFromTheKeyframes) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // tracking draws the mesh
    const fs::path d = test::makeTempDir("loop_kidnap");
    const test::CliRun r = test::runCli("fuse " + kidnapSequence().string() + " --track --loop-closure --voxel 0.03 --trajectory-online " +
                                        (d / "online.txt").string() + " --stats " + (d / "s.json").string() + " -o " + (d / "m.ply").string() + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto stats = nlohmann::json::parse(test::readText(d / "s.json"));
    const std::vector<TimedPose> online = readTumTrajectory(d / "online.txt");
    const std::vector<TimedPose> truth = readTumTrajectory(kidnapSequence() / "groundtruth.txt");
    ASSERT_EQ(online.size(), 96u);
    auto truthAt = [&](double timestamp) {
        for (const TimedPose& t : truth)
            if (std::abs(t.timestamp - timestamp) < 1e-6) return t.cameraToWorld;
        ADD_FAILURE() << "no true pose at " << timestamp;
        return Pose(Pose::Identity());
    };
    std::set<size_t> relocalisedFrames;
    for (const auto& e : stats["loop_closure"]["relocalisation"])
        if (e["relocalised"].get<bool>()) relocalisedFrames.insert(e["frame"].get<size_t>());
    std::set<size_t> lost;   // not fused: lost, or tentative (tracked from a relocalisation not yet confirmed)
    for (const auto& e : stats["tracking"]["per_frame"])
        if (e["status"] == "lost" || e["status"] == "tentative") lost.insert(e["frame"].get<size_t>());
    EXPECT_EQ(lost.size(), stats["tracking"]["lost_frames"].get<size_t>() + stats["tracking"]["tentative_frames"].get<size_t>());
    int recovered = 0;
    for (size_t jump = 56; jump < 96; jump += 4) {
        // The first frame of the run that is fused (tracked or relocalised), within 5 frames of the jump.
        for (size_t f = jump; f < jump + 4 && f < online.size(); ++f) {
            if (lost.count(f)) continue;
            const Pose want = truthAt(online[f].timestamp);
            const double metres = distanceMetres(online[f].cameraToWorld, want), degrees = angleDegrees(online[f].cameraToWorld, want);
            if (metres < 0.05 && degrees < 5.0) ++recovered;
            else ADD_FAILURE() << "frame " << f << " after the jump at " << jump << " is " << metres << " m, " << degrees << " degrees off";
            break;
        }
    }
    EXPECT_GE(recovered, 9);
    EXPECT_GE(relocalisedFrames.size(), 9u);
    EXPECT_EQ(stats["loop_closure"]["relocalisations"].get<size_t>(), relocalisedFrames.size());
    EXPECT_EQ(stats["tracking"]["relocalised_frames"].get<size_t>(), relocalisedFrames.size());
    EXPECT_EQ(stats["loop_closure"]["observations_dropped"], 0);

    // Determinism: the same frames give the same loop decisions, relocalisations, tracking verdicts and online
    // trajectory, run after run. Online decisions are causal (a frame's are made before the next frame is read), so
    // a second run of the first 60 frames must give what the run above gave for them: the jump at frame 56, its
    // relocalisation (confirmed at frame 58) and the loops decided at frames 58 and 59. Its end must not cut a
    // hypothesis open: a relocalisation's entry is completed when it is confirmed, 2 frames later. Not bit for bit
    // once a loop's corrections are re-fused (the runs then differ by about 1e-5 m; tracking alone is bit-exact,
    // tests/gpu/test_tracking.cpp), hence the trajectory's 1 mm and 0.05 degrees and the inlier shares' 0.01
    // (docs/LOOP_CLOSURE.md, "Limits"). Here every loop agrees with the trajectory, nothing is re-fused and the
    // runs agree bit for bit.
    const size_t prefix = 60;
    const test::CliRun again = test::runCli("fuse " + kidnapSequence().string() + " --track --loop-closure --frames " + std::to_string(prefix) +
                                            " --voxel 0.03 --trajectory-online " + (d / "online_prefix.txt").string() + " --stats " +
                                            (d / "s_prefix.json").string() + " -o /dev/null -q");
    ASSERT_EQ(again.exitCode, 0) << again.err;
    const auto statsAgain = nlohmann::json::parse(test::readText(d / "s_prefix.json"));
    auto before = [&](const nlohmann::json& entries) {   // those of frames before `prefix`
        nlohmann::json kept = nlohmann::json::array();
        for (const auto& e : entries)
            if (e["frame"].get<size_t>() < prefix) kept.push_back(e);
        return kept;
    };
    const nlohmann::json loops = before(stats["loop_closure"]["loops"]), loopsAgain = before(statsAgain["loop_closure"]["loops"]);
    EXPECT_GT(loops.size(), 0u) << "no loop decided before frame " << prefix << ": nothing to compare";
    ASSERT_EQ(loops.size(), loopsAgain.size());
    for (size_t i = 0; i < loops.size(); ++i)
        for (const char* key : {"frame", "keyframe_frame", "accepted", "reason"})
            EXPECT_EQ(loops[i][key], loopsAgain[i][key]) << "loop " << i << " " << key;
    const nlohmann::json relocalisations = before(stats["loop_closure"]["relocalisation"]);
    EXPECT_TRUE(std::any_of(relocalisations.begin(), relocalisations.end(), [](const nlohmann::json& e) { return e["relocalised"].get<bool>(); }))
        << "no relocalisation confirmed before frame " << prefix << ": nothing to compare";
    EXPECT_EQ(relocalisations, statsAgain["loop_closure"]["relocalisation"]);
    // Each frame's verdict and inlier share: tracking is ICP against the map's mesh, so these compare the maps.
    const nlohmann::json verdicts = before(stats["tracking"]["per_frame"]), verdictsAgain = statsAgain["tracking"]["per_frame"];
    ASSERT_EQ(verdicts.size(), verdictsAgain.size());
    for (size_t i = 0; i < verdicts.size(); ++i) {
        EXPECT_EQ(verdicts[i]["frame"], verdictsAgain[i]["frame"]) << "verdict " << i;
        EXPECT_EQ(verdicts[i]["status"], verdictsAgain[i]["status"]) << "frame " << verdicts[i]["frame"];
        EXPECT_NEAR(verdicts[i]["inlier_share"].get<double>(), verdictsAgain[i]["inlier_share"].get<double>(), 0.01) << "frame " << verdicts[i]["frame"];
    }
    const std::vector<TimedPose> onlineAgain = readTumTrajectory(d / "online_prefix.txt");
    ASSERT_EQ(onlineAgain.size(), prefix);
    for (size_t i = 0; i < prefix; ++i) {
        EXPECT_LT(distanceMetres(online[i].cameraToWorld, onlineAgain[i].cameraToWorld), 0.001) << "frame " << i;
        EXPECT_LT(angleDegrees(online[i].cameraToWorld, onlineAgain[i].cameraToWorld), 0.05) << "frame " << i;
    }
    fs::remove_all(d);
}

// The room's first 12 frames along its orbit at 320 x 240, with colour, fused into a loop closer (registration at
// 160 px): keyframes with codes and ORB features to relocalise against.
struct RoomKeyframes {
    const Intrinsics k = synth::kinectIntrinsics(320, 240);
    const std::vector<Pose> path = synth::cameraPath(40);
    const slam::LoopClosureOptions options = [] {
        slam::LoopClosureOptions o;
        o.registrationWidth = 160;
        return o;
    }();
    slam::LoopCloser closer{options};
    std::vector<std::pair<DepthImage, ColorImage>> frames;
    RoomKeyframes() {
        const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
        for (uint32_t i = 0; i < 12; ++i) {
            ColorImage color;
            DepthImage depth = room.renderDepth(k, path[i], {}, &color);
            closer.frameFused({i, &depth, &color, k, path[i]});
            frames.emplace_back(std::move(depth), std::move(color));
        }
    }
};

// Placements (LoopCloser::placements) check a tracked pose against where the frame's features put it, between a
// relocalisation and its confirmation: they must not touch what relocalisationResult refers to. (The Mapper's check
// once asked relocalisationCandidates instead, and a hypothesis confirmed after a check that found nothing named a
// candidate of an empty list: "relocalised by candidate 2 of 0", the run stopped.)
TEST(LoopCloser, PlacementsLeaveTheRelocalisationsCandidatesAsTheyWere) {
    RoomKeyframes fused;
    slam::LoopCloser& closer = fused.closer;
    const Intrinsics& k = fused.k;
    const std::vector<Pose>& path = fused.path;
    const auto& frames = fused.frames;
    const std::vector<RelocalisationCandidate> candidates = closer.relocalisationCandidates({12, &frames[5].first, &frames[5].second, k, path[0]});
    ASSERT_GE(candidates.size(), 2u);
    const uint32_t lostBefore = closer.stats().lostFrames, placedBefore = closer.stats().featureCandidates;
    // A view of the same place: placed, at the poses relocalisationCandidates gave its features' candidates.
    const std::vector<RelocalisationCandidate> placed = closer.placements({13, &frames[5].first, &frames[5].second, k, path[0]});
    ASSERT_GE(placed.size(), 1u);
    EXPECT_TRUE(placed.front().placed);
    ASSERT_TRUE(candidates.front().placed);   // the features' candidates come first
    EXPECT_TRUE(placed.front().cameraToWorld.isApprox(candidates.front().cameraToWorld, 1e-9));
    // A frame without colour: nothing placed.
    EXPECT_TRUE(closer.placements({14, &frames[5].first, nullptr, k, path[0]}).empty());
    EXPECT_EQ(closer.stats().lostFrames, lostBefore);
    EXPECT_EQ(closer.stats().featureCandidates, placedBefore);
    // The relocalisation still ends on the candidate it was found from: the last of the list.
    EXPECT_NO_THROW(closer.relocalisationResult(12, true, int(candidates.size())));
    EXPECT_EQ(closer.stats().relocalisations, 1u);
}

// The .vkloops of an earlier vkmesh (version 1: keyframes without ORB features) still loads: its keyframes are
// proposed by the ferns alone. Written here from a version 2 file by taking the features out of each keyframe, as
// version 1 laid them out (LoopCloser::save's layout). Version 2 keeps the features: a frame of a keyframe's view is
// placed by them after a save and a load.
TEST(LoopCloser, LoadsVersionOneFilesWithoutFeatures) {
    RoomKeyframes fused;
    slam::LoopCloser& closer = fused.closer;
    const Intrinsics& k = fused.k;
    const std::vector<Pose>& path = fused.path;
    const auto& frames = fused.frames;
    const slam::LoopClosureOptions& options = fused.options;
    const fs::path d = test::makeTempDir("loops_v1");
    const uint64_t mapId = 42;
    closer.save(d / "v2.vkloops", mapId);
    auto placedFor = [&](slam::LoopCloser& c) {
        size_t placed = 0;
        for (const RelocalisationCandidate& r : c.relocalisationCandidates({12, &frames[5].first, &frames[5].second, k, path[0]}))
            placed += r.placed ? 1 : 0;
        return placed;
    };
    slam::LoopCloser fromV2(options);
    fromV2.load(d / "v2.vkloops", mapId);
    EXPECT_EQ(fromV2.stats().keyframes, closer.stats().keyframes);
    const size_t placedV2 = placedFor(fromV2);
    EXPECT_GE(placedV2, 1u) << "the keyframes' features did not survive the save";

    // Version 1: the same state without each keyframe's feature block.
    const std::string file = test::readText(d / "v2.vkloops");
    const size_t header = 8 + 4 + 8 + 8 + 4;
    std::string raw(ZSTD_getFrameContentSize(file.data() + header, file.size() - header), '\0');
    ASSERT_EQ(ZSTD_decompress(raw.data(), raw.size(), file.data() + header, file.size() - header), raw.size());
    auto u32 = [&](size_t at) { uint32_t v; std::memcpy(&v, raw.data() + at, 4); return v; };
    std::string v1 = raw.substr(0, 8 + 1 + 128 + 4);
    size_t at = v1.size();
    for (uint32_t key = 0, keys = u32(8 + 1 + 128); key < keys; ++key) {
        const size_t start = at;
        at += 4 + 4;
        at += 4 + u32(at);                                    // the fern code
        const uint32_t width = u32(at), height = u32(at + 4);
        at += 8 + 16 + 8 + size_t(width) * height * 4;        // size, intrinsics, path, registration depth
        v1 += raw.substr(start, at - start);
        at += 4 + size_t(u32(at)) * (12 + 32);                // the features (version 2 only)
    }
    v1 += raw.substr(at);
    std::string packed(ZSTD_compressBound(v1.size()), '\0');
    packed.resize(ZSTD_compress(packed.data(), packed.size(), v1.data(), v1.size(), 3));
    std::string out = file.substr(0, 8);
    const uint32_t version = 1, crc = map::crc32(packed.data(), packed.size());
    const uint64_t size = packed.size();
    out.append(reinterpret_cast<const char*>(&version), 4).append(reinterpret_cast<const char*>(&mapId), 8);
    out.append(reinterpret_cast<const char*>(&size), 8).append(reinterpret_cast<const char*>(&crc), 4).append(packed);
    test::writeBytes(d / "v1.vkloops", out);
    slam::LoopCloser fromV1(options);
    fromV1.load(d / "v1.vkloops", mapId);
    EXPECT_EQ(fromV1.stats().keyframes, closer.stats().keyframes);
    EXPECT_EQ(placedFor(fromV1), 0u);   // no features: the ferns alone propose
    Pose pose;
    EXPECT_TRUE(fromV1.latestPose(11, pose));
    EXPECT_LT(distanceMetres(pose, path[11]), 1e-9);
    // A version this vkmesh does not know is refused, naming the file and the versions it reads.
    out[8] = 3;
    test::writeBytes(d / "v3.vkloops", out);
    const std::string why = test::errorMessageOf([&] { slam::LoopCloser(options).load(d / "v3.vkloops", mapId); });
    EXPECT_NE(why.find("v3.vkloops is version 3; this vkmesh reads versions 1 to 2"), std::string::npos) << why;
    fs::remove_all(d);
}

// A false loop: two identical groups of objects 4.5 m apart (synth --scene twins), the second seen from the very
// viewpoints the first was. The ferns find them alike; every such loop is rejected (the registration from the old
// keyframe's pose fits, but moves the camera further than tracking can have drifted), and the final trajectory is
// the tracked one: the map is not bent.
TEST(LoopClosure, TwinPlacesDoNotCloseAFalseLoop) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const fs::path d = test::makeTempDir("loop_twins");
    test::CliRun r = test::runCli("synth " + (d / "seq").string() + " --scene twins --path twin-visit --frames 200 --noise --width 320 --height 240 "
                                  "--gt-spacing 0.05");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    r = test::runCli("fuse " + (d / "seq").string() + " --track --loop-closure --voxel 0.03 --trajectory " + (d / "final.txt").string() +
                     " --trajectory-online " + (d / "online.txt").string() + " --stats " + (d / "s.json").string() + " -o /dev/null -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto stats = nlohmann::json::parse(test::readText(d / "s.json"));
    EXPECT_EQ(stats["tracking"]["lost_frames"], 0);
    int twinLoops = 0;
    for (const auto& loop : stats["loop_closure"]["loops"]) {
        // Frame i + 150 sees the second group from where frame i saw the first.
        if (loop["frame"].get<int>() - loop["keyframe_frame"].get<int>() < 100) continue;
        ++twinLoops;
        EXPECT_FALSE(loop["accepted"].get<bool>()) << loop.dump();
    }
    EXPECT_GT(twinLoops, 0) << "the ferns found no look-alike: the test tests nothing";
    const std::vector<TimedPose> online = readTumTrajectory(d / "online.txt"), final = readTumTrajectory(d / "final.txt");
    ASSERT_EQ(online.size(), final.size());
    for (size_t i = 0; i < online.size(); ++i)
        EXPECT_LT(distanceMetres(online[i].cameraToWorld, final[i].cameraToWorld), 0.02) << "frame " << i << " was moved";
    fs::remove_all(d);
}

// The keyframes and the pose graph are saved with the map: a run continued from it relocalises a jump to a place
// only the first run saw. A corrupt or foreign state is refused naming the file.
TEST(LoopClosure, KeyframesAreSavedWithTheMap) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const fs::path d = test::makeTempDir("loop_save");
    const std::string seq = kidnapSequence().string(), map = (d / "m.vkmap").string();
    test::CliRun r = test::runCli("fuse " + seq + " --track --loop-closure --frames 56 --voxel 0.03 --save " + map + " --stats " +
                                  (d / "a.json").string() + " -o /dev/null -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    ASSERT_TRUE(fs::exists(d / "m.vkloops"));
    const auto first = nlohmann::json::parse(test::readText(d / "a.json"))["loop_closure"];
    // Frames 56-63: the first is the jump to lap 2 (frame 72 of the rendered path).
    r = test::runCli("fuse " + seq + " --track --loop-closure --load " + map + " --first-frame 56 --frames 64 --stats " + (d / "b.json").string() +
                     " -o /dev/null -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto second = nlohmann::json::parse(test::readText(d / "b.json"))["loop_closure"];
    EXPECT_GT(second["keyframes"].get<int>(), first["keyframes"].get<int>());
    EXPECT_GE(second["relocalisations"].get<int>(), 1);

    std::string bytes = test::readText(d / "m.vkloops");
    bytes[bytes.size() / 2] ^= 0x5a;
    test::writeBytes(d / "m.vkloops", bytes);
    r = test::runCli("fuse " + seq + " --track --loop-closure --load " + map + " --first-frame 56 --frames 60 -o /dev/null -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("m.vkloops is corrupt"), std::string::npos) << r.err;
    test::writeBytes(d / "m.vkloops", bytes.substr(0, 30));
    r = test::runCli("fuse " + seq + " --track --loop-closure --load " + map + " --first-frame 56 --frames 60 -o /dev/null -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("m.vkloops is truncated"), std::string::npos) << r.err;
    fs::remove_all(d);
}

// The drift sequence (synth --scene gallery: a 13 m hall circled looking outward; tracking drifts before the start
// comes back into view). Frame-to-model tracking snaps back onto the start's surfaces before a keyframe there is
// recognised, so the loops found there agree with the trajectory: loop closure must then leave the trajectory as
// tracking made it (no loop may bend it), lose no frame and recognise the start. (The target, 3x lower ATE
// with loop closure, is not met: docs/LOOP_CLOSURE.md, "Limits".) The lap in 200 frames, not bench/loop_bench.sh's
// 300: the camera moves faster and tracking drifts more (up to 9.1 cm, 192 keyframes, 115 loops detected; at 300
// frames 6.4 cm, 146, 78), and the test takes a third less time (rendering is ~0.15 s of CPU a frame).
TEST(LoopClosure, DriftingGalleryIsNotMadeWorse) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const fs::path d = test::makeTempDir("loop_gallery");
    test::CliRun r = test::runCli("synth " + (d / "seq").string() + " --scene gallery --path gallery-loop --frames 200 --noise --width 320 "
                                  "--height 240 --gt-spacing 0.05");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    r = test::runCli("fuse " + (d / "seq").string() + " --track --loop-closure --voxel 0.03 --stats " + (d / "s.json").string() + " -o /dev/null -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto stats = nlohmann::json::parse(test::readText(d / "s.json"));
    EXPECT_EQ(stats["tracking"]["lost_frames"], 0);
    const double online = stats["tracking"]["position_error_m"]["rmse"], final = stats["loop_closure"]["position_error_m"]["rmse"];
    EXPECT_GT(stats["tracking"]["position_error_m"]["max"].get<double>(), 0.05) << "the sequence no longer drifts";
    EXPECT_LE(final, online + 0.001);
    EXPECT_GT(stats["loop_closure"]["keyframes"].get<int>(), 100);
    EXPECT_GT(stats["loop_closure"]["loops_detected"].get<int>(), 0);
    EXPECT_EQ(stats["loop_closure"]["observations_dropped"], 0);
    fs::remove_all(d);
}

// The data lines of a TUM-layout text file (depth.txt, rgb.txt, groundtruth.txt) of `folder`.
std::vector<io::text::TextLine> dataLines(const fs::path& folder, const char* file) {
    std::ifstream in = io::text::openText(folder / file);
    return io::text::readDataLines(in, (folder / file).string());
}

// A real sequence made of ICL-NUIM office 0's frames in the order `frames` (numbers of the data lines of its depth.txt):
// cut, reversed and joined as ../shared/docs/real-data.md says, each frame with its colour image and its true pose,
// under new timestamps (2, 8, 14, ...: vkmesh reads frames in time order). bench/real_kidnaps.py (make, mirror)
// makes the same from any TUM-layout dataset and scores runs on them. `name` must keep the word "icl" (the camera
// preset).
fs::path iclSequence(const fs::path& source, const fs::path& dir, const std::string& name, const std::vector<size_t>& frames) {
    const auto depth = dataLines(source, "depth.txt"), rgb = dataLines(source, "rgb.txt"), truth = dataLines(source, "groundtruth.txt");
    std::map<std::string, std::string> poseAt;   // ICL-NUIM: one pose per frame, at its timestamp (the frame index)
    for (const auto& t : truth) {
        std::string pose;
        for (size_t i = 1; i < t.tokens.size(); ++i) pose += " " + t.tokens[i];
        poseAt[t.tokens[0]] = pose;
    }
    EXPECT_EQ(rgb.size(), depth.size()) << "ICL-NUIM pairs every depth image with the colour image of its timestamp";
    const fs::path out = dir / name;
    fs::create_directories(out);
    std::ofstream d(out / "depth.txt"), c(out / "rgb.txt"), g(out / "groundtruth.txt");
    for (size_t k = 0; k < frames.size(); ++k) {
        const size_t f = frames[k];
        const std::string stamp = std::to_string(2 + 6 * k);
        const std::string& time = depth.at(f).tokens.at(0);
        d << stamp << " " << depth[f].tokens.at(1) << "\n";
        c << stamp << " " << rgb.at(f).tokens.at(1) << "\n";
        EXPECT_EQ(poseAt.count(time), 1u) << "frame " << f << " has no true pose";
        g << stamp << poseAt[time] << "\n";
    }
    for (const char* folder : {"depth", "rgb"}) fs::create_directory_symlink(source / folder, out / folder);
    return out;
}

// A TUM RGB-D sequence of the given frames of `source` (its depth.txt's data lines, 0-based): their depth lines, the
// whole rgb.txt (each depth frame is paired with the colour image nearest in time), and for each kept frame the
// ground-truth line nearest in time, so that groundtruth.txt holds one pose per frame, in order (runOnRealSequence
// compares them by position). `name` must keep "fr1": the folder's name picks the camera preset.
fs::path tumSequence(const fs::path& source, const fs::path& dir, const std::string& name, const std::vector<size_t>& frames) {
    const auto depth = dataLines(source, "depth.txt"), truth = dataLines(source, "groundtruth.txt");
    const fs::path out = dir / name;
    fs::create_directories(out);
    fs::copy_file(source / "rgb.txt", out / "rgb.txt");
    std::ofstream d(out / "depth.txt"), g(out / "groundtruth.txt");
    for (const size_t f : frames) {
        const std::string& time = depth.at(f).tokens.at(0);
        d << time << " " << depth[f].tokens.at(1) << "\n";
        const auto nearest = std::min_element(truth.begin(), truth.end(), [&](const auto& a, const auto& b) {
            return std::abs(std::stod(a.tokens.at(0)) - std::stod(time)) < std::abs(std::stod(b.tokens.at(0)) - std::stod(time));
        });
        EXPECT_LT(std::abs(std::stod(nearest->tokens.at(0)) - std::stod(time)), 0.01) << "frame " << f << " has no true pose near it";
        for (size_t i = 0; i < nearest->tokens.size(); ++i) g << (i ? " " : "") << nearest->tokens[i];
        g << "\n";
    }
    for (const char* folder : {"depth", "rgb"}) fs::create_directory_symlink(source / folder, out / folder);
    return out;
}

std::vector<size_t> frameRange(size_t first, size_t last) {   // first..last, either way
    std::vector<size_t> v;
    for (size_t f = first;; f = first <= last ? f + 1 : f - 1) {
        v.push_back(f);
        if (f == last) return v;
    }
}

std::vector<size_t> joined(std::initializer_list<std::vector<size_t>> parts) {
    std::vector<size_t> v;
    for (const auto& p : parts) v.insert(v.end(), p.begin(), p.end());
    return v;
}

// A tracked run with loop closure on a real sequence, and what a user needs of it: the frames each verdict gave
// (fused: tracked or relocalised), every fused frame within 5 cm of its true place, and the confirmed relocalisations
// within 5 cm and 5 degrees.
struct RealRun {
    nlohmann::json stats;
    std::vector<TimedPose> online, truth;
    std::set<size_t> fused, notFused, relocalised;
};

RealRun runOnRealSequence(const fs::path& seq, const fs::path& d) {
    RealRun run;
    const test::CliRun r = test::runCli("fuse " + seq.string() + " --track --loop-closure --voxel 0.02 --trajectory-online " +
                                        (d / "online.txt").string() + " --stats " + (d / "s.json").string() + " -o /dev/null -q");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    if (r.exitCode != 0) return run;
    run.stats = nlohmann::json::parse(test::readText(d / "s.json"));
    run.online = readTumTrajectory(d / "online.txt");
    run.truth = readTumTrajectory(seq / "groundtruth.txt");
    EXPECT_EQ(run.online.size(), run.truth.size());
    for (const auto& v : run.stats["tracking"]["per_frame"]) {
        const size_t f = v["frame"].get<size_t>();
        const bool isFused = v["status"] == "tracked" || v["status"] == "relocalised";
        (isFused ? run.fused : run.notFused).insert(f);
        if (v["status"] == "relocalised") run.relocalised.insert(f);
        if (!isFused || f >= run.online.size() || f >= run.truth.size()) continue;
        EXPECT_LT(distanceMetres(run.online[f].cameraToWorld, run.truth[f].cameraToWorld), 0.05)
            << "frame " << f << " (" << v["status"] << ", inlier share " << v["inlier_share"] << ") fused off its place";
        if (v["status"] == "relocalised") {
            EXPECT_LT(angleDegrees(run.online[f].cameraToWorld, run.truth[f].cameraToWorld), 5.0) << "frame " << f << " relocalised off";
        }
    }
    return run;
}

// What issue 54 asks of a jump onto a mapped place: reported within 2 frames of the landing (not fused), relocalised
// within 5 (the frame that confirms it).
void expectReportedAndRelocalised(const RealRun& run, size_t landing) {
    EXPECT_TRUE(run.notFused.count(landing) || run.notFused.count(landing + 1) || run.notFused.count(landing + 2))
        << "the jump at frame " << landing << " went unnoticed";
    bool relocalised = false;
    for (size_t f = landing; f <= landing + 5; ++f) relocalised = relocalised || run.relocalised.count(f) > 0;
    EXPECT_TRUE(relocalised) << "the jump at frame " << landing << " was not relocalised within 5 frames";
}

// Real data (../shared/docs/real-data.md): ICL-NUIM office traj0's frames 0-58, 99-129 and 160-185: two jumps to views
// that no kept frame saw from within 30 cm and 30 degrees. The first (113 cm, 98 degrees) is noticed at once (the
// landing frame is lost) and nothing is fused at a wrong place (runOnRealSequence: every fused frame within 5 cm of
// the truth, every relocalised one within 5 degrees too). Before relocalisations were tentative (MapperOptions::
// Relocalisation), frame 93 of the recording settled on a look-alike 108 cm off (65 % of its pixels matching, at 3.6
// times the inlier RMSE of the frames before the loss) and tracking went on from there. With the ferns alone the
// camera then stayed lost (71 frames); the landing view's ORB features match a keyframe's that sees the same wall from
// far off, and the pose they give is confirmed by tracking (measured: relocalised at the landing, confirmed 2 frames
// later, 1 cm off). The second (72 cm, 49 degrees, frame 90 here) lands on a wall (70 % of the landing's depth within
// 2 cm of one plane): relocalised at the landing, 1.3 cm off, but tracking from there slid 9-10 cm along the wall with
// an RMSE as good as the frames' before the loss, and the confirming frame was fused 10 cm off, until a hypothesis's
// frames had to agree with where their own features place them (Mapper::placedElsewhere; measured 2026-12-07: the
// confirming frame's features put it 8.5 cm from tracking, it was found again from them and fused 1.0 cm off).
TEST(RealLoopClosure, IclKidnapIntoAnUnmappedPlaceIsNotFusedAtAWrongPlace) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const fs::path d = test::makeTempDir("real_kidnap_icl");
    const std::vector<size_t> frames = joined({frameRange(0, 58), frameRange(99, 129), frameRange(160, 185)});
    const RealRun run = runOnRealSequence(iclSequence(*root / "iclnuim_office_traj0", d, "icl_cut", frames), d);
    ASSERT_EQ(run.online.size(), 116u);
    for (size_t landing : {59u, 90u})
        EXPECT_TRUE(run.notFused.count(landing) || run.notFused.count(landing + 1) || run.notFused.count(landing + 2))
            << "the jump at frame " << landing << " went unnoticed";
    EXPECT_EQ(run.fused.size() + run.notFused.size(), 115u);   // every frame after the first has a verdict
    EXPECT_GE(run.fused.size(), 106u);                         // found again within a few frames
    // The first landing, which the ferns alone never found: placed by the features. (The wall's was found from a
    // keyframe the ferns named, and its frames again from the features' and the ferns' candidates.)
    bool firstPlaced = false;
    for (const auto& e : run.stats["loop_closure"]["relocalisation"])
        if (e["frame"] == 59) firstPlaced = e["relocalised"].get<bool>() && e["placed"].get<bool>();
    EXPECT_TRUE(firstPlaced) << run.stats["loop_closure"]["relocalisation"].dump();
    EXPECT_EQ(run.relocalised.size(), 2u);
    EXPECT_GE(run.stats["loop_closure"]["relocalisations_by_features"].get<size_t>(), 1u);
    fs::remove_all(d);
}

// Real data: ICL-NUIM office 0 there and back (frames 0-119, then 118-0, ../shared/docs/real-data.md), with two runs
// of 25 frames cut out of the way back: jumps of 84 cm / 39 degrees and 35 cm / 77 degrees onto places the way there
// mapped. Each jump is reported within 2 frames (lost or tentative) and relocalised within 5 frames, within 5 cm and
// 5 degrees (measured: both confirmed 2 frames after the landing, 1.1 cm off); no frame is fused more than 5 cm off.
// The way back's images are the way there's, so the ferns see the same images: this tests tracking's loss and the
// verification of relocalisations on real frames, not place recognition.
TEST(RealLoopClosure, IclThereAndBackKidnapsOntoMappedPlacesAreRelocalised) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const fs::path d = test::makeTempDir("real_back_icl");
    // Frames 0-134 of the sequence (0-119, 118-104), then its frames 160-184 (orig. 78-54), then 210-238 (28-0).
    const std::vector<size_t> frames = joined({frameRange(0, 119), frameRange(118, 104), frameRange(78, 54), frameRange(28, 0)});
    const RealRun run = runOnRealSequence(iclSequence(*root / "iclnuim_office_traj0", d, "icl_back", frames), d);
    ASSERT_EQ(run.online.size(), 189u);
    for (size_t landing : {135u, 160u}) {
        expectReportedAndRelocalised(run, landing);
    }
    EXPECT_EQ(run.relocalised.size(), 2u);
    EXPECT_GE(run.fused.size(), 175u);
    fs::remove_all(d);
}

// Real data, issue 54's "a real revisit within 5 cm and 20 degrees after 3 m of travel is proposed and verified": ICL-NUIM
// office 0's even frames 0-100 on the way there and its odd frames 99-1 on the way back (../shared/docs/real-data.md,
// "a revisit"), 4.9 m in all. The way back's images are not the way there's: each is the recording's frame between two
// of them, 2 cm and 3-4 degrees from its neighbours. Loops are proposed and verified between the way back and the way
// there (measured 2026-12-07: 16 verified, 6 of them within 5 cm and 20 degrees after 3.4-4.5 m of travel, all
// "consistent": tracking against the map leaves no drift for them to correct); each verified loop pairs views that
// overlap, no frame is fused more than 5 cm off (runOnRealSequence), and the loops leave the trajectory no worse.
TEST(RealLoopClosure, IclRevisitAfterFiveMetresIsProposedAndVerified) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const fs::path d = test::makeTempDir("real_revisit_icl");
    std::vector<size_t> frames;
    for (size_t f = 0; f <= 100; f += 2) frames.push_back(f);
    for (int f = 99; f >= 1; f -= 2) frames.push_back(size_t(f));
    const RealRun run = runOnRealSequence(iclSequence(*root / "iclnuim_office_traj0", d, "icl_revisit", frames), d);
    ASSERT_EQ(run.truth.size(), 101u);
    ASSERT_EQ(run.online.size(), 101u);
    std::vector<double> travelled(1, 0.0);   // metres along the true path up to each frame
    for (size_t i = 1; i < run.truth.size(); ++i) travelled.push_back(travelled.back() + distanceMetres(run.truth[i - 1].cameraToWorld, run.truth[i].cameraToWorld));
    EXPECT_GT(travelled.back(), 4.5);
    size_t verified = 0, revisits = 0;
    for (const auto& loop : run.stats["loop_closure"]["loops"]) {
        if (!loop["accepted"].get<bool>()) continue;
        ++verified;
        const size_t i = loop["frame"].get<size_t>(), j = loop["keyframe_frame"].get<size_t>();
        const Pose& a = run.truth.at(i).cameraToWorld;
        const Pose& b = run.truth.at(j).cameraToWorld;
        const double axisDegrees = std::acos(std::clamp(a.block<3, 1>(0, 2).dot(b.block<3, 1>(0, 2)), -1.0, 1.0)) * 180.0 / std::numbers::pi;
        EXPECT_LT(distanceMetres(a, b), 0.3) << "a loop verified between frames " << i << " and " << j;   // measured up to 0.24 m
        EXPECT_LT(axisDegrees, 30.0) << "a loop verified between frames " << i << " and " << j;            // measured up to 7.3
        if (distanceMetres(a, b) <= 0.05 && angleDegrees(a, b) <= 20.0 && travelled[i] - travelled[j] >= 3.0) ++revisits;
    }
    EXPECT_GE(revisits, 3u) << verified << " loops verified, too few of them the revisit's";
    EXPECT_GE(run.fused.size(), 95u);
    EXPECT_LE(run.stats["loop_closure"]["position_error_m"]["rmse"].get<double>(), run.stats["tracking"]["position_error_m"]["rmse"].get<double>() + 0.001);
    fs::remove_all(d);
}

// Real data: TUM fr1/rpy's frames 234-260, then 300-329: the Kinect, turning in place, lands 122 degrees (9 cm) from
// where it was, looking at a place its frames near 239 mapped (as `bench/real_kidnaps.py --auto 4`'s fourth kidnap,
// which with the ferns alone stayed lost for 26 frames: no keyframe looks alike to them). The landing frame's ORB
// features are matched to a keyframe's and solved by PnP; tracking from that pose agrees with it and the
// relocalisation is confirmed 2 frames later (measured: 1.2 cm off at the landing). The old map is drifted, and the
// landing matches it 2-2.7 times worse than the frames before the loss matched theirs: within the bound for placed
// candidates (MapperOptions::Relocalisation::placedMaxErrorRatio), over the 1.5 for the others. Every fused frame
// within 5 cm (measured: up to 4.2 cm, TUM's own tracking drift before the jump).
TEST(RealLoopClosure, TumLandingTurnedPastTheFernsIsPlacedByFeatures) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const fs::path d = test::makeTempDir("real_kidnap_tum");
    const RealRun run = runOnRealSequence(tumSequence(*root / "tum_fr1_rpy", d, "fr1_cut", joined({frameRange(234, 260), frameRange(300, 329)})), d);
    ASSERT_EQ(run.online.size(), 57u);
    const size_t landing = 27;
    expectReportedAndRelocalised(run, landing);
    EXPECT_GE(run.stats["loop_closure"]["relocalisations_by_features"].get<size_t>(), 1u);
    EXPECT_GE(run.fused.size(), 50u);
    fs::remove_all(d);
}

// Real data: the first 220 frames of TUM fr1/rpy, a Kinect rolling, pitching and turning in place, see the same
// places again rolled 10-70 degrees. Random ferns do not propose them (at Kinect quality a view turned 10-20 degrees
// differs in 41-71 % of its ferns, over the 30 % threshold: docs/RESULTS.md, "Place recognition"); the keyframes
// the pose graph puts nearby are proposed and verified (measured: frames 196, 207 and 216, rolled 52, 73 and 14
// degrees from their keyframes, ferns 44-70 % apart). Every verified loop pairs views that truly overlap (optical
// axes within 30 degrees, cameras within 15 cm), and closing loops does not make the trajectory worse.
TEST(RealLoopClosure, TumRevisitsTheFernsMissAreProposedByPlace) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const fs::path seq = *root / "tum_fr1_rpy", d = test::makeTempDir("real_revisit_tum");
    const test::CliRun r = test::runCli("fuse " + seq.string() + " --frames 220 --track --loop-closure --voxel 0.02 --stats " +
                                        (d / "s.json").string() + " -o /dev/null -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto stats = nlohmann::json::parse(test::readText(d / "s.json"));
    const auto dataset = Dataset::open(seq);
    const slam::LoopClosureOptions defaults;
    int missedByFerns = 0;
    for (const auto& loop : stats["loop_closure"]["loops"]) {
        if (!loop["accepted"].get<bool>()) continue;
        const Pose a = dataset->frame(loop["frame"].get<size_t>()).cameraToWorld;
        const Pose b = dataset->frame(loop["keyframe_frame"].get<size_t>()).cameraToWorld;
        const double axisDegrees = std::acos(std::clamp(a.block<3, 1>(0, 2).dot(b.block<3, 1>(0, 2)), -1.0, 1.0)) * 180.0 / std::numbers::pi;
        EXPECT_LT(distanceMetres(a, b), 0.15) << "a loop verified between frames " << loop["frame"] << " and " << loop["keyframe_frame"];
        EXPECT_LT(axisDegrees, 30.0) << "a loop verified between frames " << loop["frame"] << " and " << loop["keyframe_frame"];
        if (loop["proposed_by"] == "proximity" && loop["dissimilarity"].get<double>() > defaults.loopDissimilarity && angleDegrees(a, b) >= 10.0)
            ++missedByFerns;
    }
    EXPECT_GE(missedByFerns, 1) << "no verified revisit turned 10 degrees or more that the ferns miss";
    EXPECT_EQ(stats["tracking"]["lost_frames"], 0);
    EXPECT_LE(stats["loop_closure"]["position_error_m"]["rmse"].get<double>(), stats["tracking"]["position_error_m"]["rmse"].get<double>() + 0.001);
    fs::remove_all(d);
}

// Real data: ORB features and PnP place TUM fr1/rpy's views of one place turned 10-30 degrees from a keyframe, which
// the ferns do not propose (docs/RESULTS.md, "Place recognition on real pairs": none under 30 % dissimilarity), and
// propose nothing for views of other places. Pairs of frames at least 30 apart by their true relative pose, spread
// over the sequence; "right" within 5 cm and 5 degrees of the true relative pose (TUM's own tracked relative poses
// are off by 1-5 cm).
TEST(FeatureRelocaliser, PlacesRealViewsTurnedPastTheFernsAndNotOtherPlaces) {
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const auto dataset = Dataset::open(*root / "tum_fr1_rpy");
    const size_t n = dataset->size();
    std::vector<std::pair<size_t, size_t>> same, other;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 30; j < n; ++j) {
            const Pose a = dataset->frame(i).cameraToWorld, b = dataset->frame(j).cameraToWorld;
            const double axisDegrees = std::acos(std::clamp(a.block<3, 1>(0, 2).dot(b.block<3, 1>(0, 2)), -1.0, 1.0)) * 180.0 / std::numbers::pi;
            if (distanceMetres(a, b) < 0.10 && angleDegrees(a, b) >= 10.0 && angleDegrees(a, b) < 30.0) same.emplace_back(i, j);
            else if (axisDegrees > 45.0 || distanceMetres(a, b) > 1.0) other.emplace_back(i, j);
        }
    ASSERT_GE(same.size(), 1000u);
    ASSERT_GE(other.size(), 1000u);
    std::map<size_t, std::pair<DepthImage, ColorImage>> images;
    auto frame = [&](size_t i) -> const std::pair<DepthImage, ColorImage>& {
        auto it = images.find(i);
        if (it == images.end()) {
            DepthImage depth = dataset->loadDepth(i);
            ColorImage color = dataset->loadColor(i, nullptr, &depth);
            it = images.emplace(i, std::make_pair(std::move(depth), std::move(color))).first;
        }
        return it->second;
    };
    const slam::FeatureRelocaliser features;
    const Intrinsics k = dataset->intrinsics();
    const int pairs = 24;
    int sameProposed = 0, sameRight = 0, otherProposed = 0;
    for (int p = 0; p < pairs; ++p) {
        const auto [i, j] = same[size_t(p) * same.size() / pairs];
        const slam::KeyframeFeatures keyframe = features.describe(frame(i).first, &frame(i).second, k);
        EXPECT_GE(keyframe.count(), 200u) << "frame " << i;
        const std::vector<slam::FeatureCandidate> found = features.propose(&frame(j).second, k, {&keyframe});
        if (found.empty()) continue;
        ++sameProposed;
        ASSERT_EQ(found.front().keyframe, 0);
        const Pose truth = inverseRigid(dataset->frame(i).cameraToWorld) * dataset->frame(j).cameraToWorld;
        const Pose error = inverseRigid(truth) * inverseRigid(found.front().keyframeToCamera);
        if (translationMetres(error) < 0.05 && rotationDegrees(error) < 5.0) ++sameRight;
        // Deterministic: the same frames give the same pose.
        if (p == 0) {
            EXPECT_EQ(features.propose(&frame(j).second, k, {&keyframe}).front().keyframeToCamera, found.front().keyframeToCamera);
        }
    }
    for (int p = 0; p < pairs; ++p) {
        const auto [i, j] = other[size_t(p) * other.size() / pairs];
        const slam::KeyframeFeatures keyframe = features.describe(frame(i).first, &frame(i).second, k);
        otherProposed += features.propose(&frame(j).second, k, {&keyframe}).empty() ? 0 : 1;
    }
    // Measured: 15 placed, 13 of them right (of all TUM pairs turned 10-30 degrees: 83 % placed, 71 % right).
    EXPECT_GE(sameProposed, pairs / 2) << "of " << pairs << " views turned 10-30 degrees (" << sameRight << " right)";
    EXPECT_GE(sameRight, pairs * 5 / 12) << "of " << pairs << " views turned 10-30 degrees (" << sameProposed << " placed)";
    EXPECT_LE(otherProposed, 1) << "of " << pairs << " views of other places";
    // Without colour there are no features: nothing is proposed, and the ferns alone relocalise.
    EXPECT_EQ(features.describe(frame(0).first, nullptr, k).count(), 0u);
    EXPECT_TRUE(features.propose(nullptr, k, {}).empty());
    ColorImage wrongSize = frame(0).second;
    wrongSize.width /= 2;
    EXPECT_NE(test::errorMessageOf([&] { features.describe(frame(0).first, &wrongSize, k); }).find("colour image is"), std::string::npos);
    ColorImage shortBytes = frame(0).second;
    shortBytes.rgb.resize(10);
    EXPECT_NE(test::errorMessageOf([&] { features.describe(frame(0).first, &shortBytes, k); }).find("holds 10 bytes"), std::string::npos);
}

// Bad combinations are clear errors.
TEST(LoopClosure, OptionsNeedTracking) {
    const fs::path seq = test::makeMinimalTum("loop_options");   // refused before any frame is read
    // Options, and what the error must say.
    const std::pair<const char*, const char*> refused[] = {
        {"--loop-closure", "need --track"},
        {"--track --no-loop-closure --corrections-per-frame 3", "--corrections-per-frame needs loop closure"},
        {"--track --no-loop-closure --loop-place-candidates 0", "--loop-place-candidates needs loop closure"},
        {"--track --no-keep-frames --loop-place-candidates 0", "--loop-place-candidates needs loop closure"},
        {"--track --loop-closure --no-loop-closure", "contradict"},
        {"--track --loop-closure --loop-place-candidates 101", "--loop-place-candidates"},
    };
    for (const auto& [options, says] : refused) {
        const test::CliRun r = test::runCli("fuse " + seq.string() + " " + options + " -o /dev/null");
        EXPECT_NE(r.exitCode, 0) << options;
        EXPECT_NE(r.err.find(says), std::string::npos) << options << ": " << r.err;
    }
    // --track's default loop closure steps aside, with a note, for frames smaller than place recognition's image
    // (16 x 12 here: tracking takes 8 x 8 and more); asked for with --loop-closure, the run stops with the reason.
    const fs::path small = test::makeMinimalTum("loop_small", 3, 16, 12);
    test::CliRun r = test::runCli("fuse " + small.string() + " --track -o /dev/null");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("no loop closure or relocalisation: the 16x12 frames"), std::string::npos) << r.err;
    r = test::runCli("fuse " + small.string() + " --track --loop-closure -o /dev/null");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("16x12 depth image cannot shrink"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace vkmesh
