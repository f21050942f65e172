// Quality evaluation against ground truth (src/eval): area sampling, the exact capped nearest-neighbour
// search, the metrics on surfaces with known answers, the "seen by the sequence" mask on a rendered
// sequence, and `vkmesh eval` end to end (when the program has the command).
#include "eval/evaluate.h"

#include "io/dataset.h"
#include "io/ply.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>

using namespace vkmesh;
using namespace vkmesh::eval;
namespace fs = std::filesystem;

namespace {

// The rectangle [x0, x1] x [y0, y1] in the plane z, as two triangles.
Mesh rectangle(double x0, double x1, double y0, double y1, double z = 0) {
    Mesh m;
    m.positions = {Eigen::Vector3f(x0, y0, z), Eigen::Vector3f(x1, y0, z), Eigen::Vector3f(x1, y1, z),
                   Eigen::Vector3f(x0, y1, z)};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// Ground truth as a synthetic sequence writes it: a regular lattice every `spacing` on [0, 1] x [0, 1], z = 0.
std::vector<Eigen::Vector3f> latticeSquare(double spacing) {
    std::vector<Eigen::Vector3f> points;
    const int n = int(std::lround(1.0 / spacing));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) points.emplace_back((i + 0.5) * spacing, (j + 0.5) * spacing, 0.0);
    return points;
}

const ThresholdScores& scoreAt(const EvalResult& r, double threshold) {
    for (const auto& s : r.scores)
        if (std::abs(s.threshold - threshold) < 1e-12) return s;
    throw std::runtime_error("no score at threshold " + std::to_string(threshold));
}

}  // namespace

TEST(SampleByArea, DensityFollowsAreaNotVertices) {
    const double spacing = 0.02;  // 2500 samples per square metre
    const auto square = sampleByArea(rectangle(0, 1, 0, 1), spacing, 1);
    const auto wide = sampleByArea(rectangle(0, 2, 0, 1), spacing, 1);
    EXPECT_NEAR(double(square.size()), 2500.0, 2500 * 0.01);
    EXPECT_NEAR(double(wide.size()) / double(square.size()), 2.0, 0.04);
    for (const auto& p : wide) {
        ASSERT_EQ(p.z(), 0.0f);
        ASSERT_GE(p.x(), 0.0f);
        ASSERT_LE(p.x(), 2.0f);
        ASSERT_GE(p.y(), 0.0f);
        ASSERT_LE(p.y(), 1.0f);
    }

    // The same 2 x 1 rectangle as a fan of very unequal triangles around a vertex near one corner, with many
    // vertices crowded on the left edge: the samples still spread evenly over the area.
    Mesh fan;
    fan.positions.emplace_back(1.9f, 0.05f, 0.0f);  // fan centre
    std::vector<Eigen::Vector2f> rim;
    for (int k = 0; k <= 40; ++k) rim.emplace_back(0.0f, 1.0f - k / 40.0f);  // left edge, top to bottom, dense
    rim.emplace_back(2.0f, 0.0f);
    rim.emplace_back(2.0f, 1.0f);
    rim.emplace_back(0.0f, 1.0f);
    for (const auto& r : rim) fan.positions.emplace_back(r.x(), r.y(), 0.0f);
    for (uint32_t k = 1; k + 1 < fan.positions.size(); ++k) fan.triangles.push_back({0, k, k + 1});
    const auto fanSamples = sampleByArea(fan, 0.01, 3);  // 20000 expected
    EXPECT_NEAR(double(fanSamples.size()), 20000.0, 200.0);
    std::vector<int> bins(8, 0);
    for (const auto& p : fanSamples) bins[std::clamp(int(p.x() / 0.25f), 0, 7)]++;
    for (int b = 0; b < 8; ++b) EXPECT_NEAR(bins[b], fanSamples.size() / 8.0, fanSamples.size() / 8.0 * 0.06) << "bin " << b;
    int bottom = 0;
    for (const auto& p : fanSamples) bottom += p.y() < 0.5f;
    EXPECT_NEAR(bottom, fanSamples.size() / 2.0, fanSamples.size() * 0.02);
}

TEST(SampleByArea, SamplesLieOnTheirTriangles) {
    Mesh m;
    m.positions = {Eigen::Vector3f(0.1f, -0.2f, 0.3f), Eigen::Vector3f(0.9f, 0.1f, 0.5f), Eigen::Vector3f(0.2f, 0.7f, -0.4f)};
    m.triangles = {{0, 1, 2}};
    const Eigen::Vector3d a = m.positions[0].cast<double>(), b = m.positions[1].cast<double>(),
                          c = m.positions[2].cast<double>();
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const auto samples = sampleByArea(m, 0.01, 5);
    EXPECT_NEAR(double(samples.size()), area / 1e-4, 1.0);  // floor + one Bernoulli
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& s : samples) {
        const Eigen::Vector3d p = s.cast<double>();
        ASSERT_LT(std::abs((p - a).dot(n)), 1e-6);
        // Barycentric coordinates within [0, 1].
        Eigen::Matrix<double, 3, 2> e;
        e << b - a, c - a;
        const Eigen::Vector2d uv = e.colPivHouseholderQr().solve(p - a);
        ASSERT_GE(uv.x(), -1e-6);
        ASSERT_GE(uv.y(), -1e-6);
        ASSERT_LE(uv.x() + uv.y(), 1 + 1e-6);
        centroid += p;
    }
    centroid /= double(samples.size());
    EXPECT_LT((centroid - (a + b + c) / 3).norm(), 0.01);  // uniform: the samples' mean is the centroid

    // Deterministic per seed; another seed gives other points.
    EXPECT_EQ(sampleByArea(m, 0.01, 5), samples);
    EXPECT_NE(sampleByArea(m, 0.01, 6), samples);
    // A point cloud is used as it is; bad spacing and bad indices are errors.
    Mesh cloud;
    cloud.positions = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
    EXPECT_EQ(sampleByArea(cloud, 0.005, 1), cloud.positions);
    EXPECT_THROW(sampleByArea(m, 0.0, 1), Error);
    Mesh bad = m;
    bad.triangles = {{0, 1, 3}};
    EXPECT_THROW(sampleByArea(bad, 0.01, 1), Error);
}

TEST(NearestDistances, ExactAgainstBruteForce) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<Eigen::Vector3f> points;
    // Two surfaces (a plane and a sphere) and a sparse scatter, like GT with outliers.
    for (int i = 0; i < 6000; ++i) points.emplace_back(u(rng), u(rng), 0.3f * u(rng) * 0.01f);
    for (int i = 0; i < 6000; ++i) points.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized() * 0.4f +
                                                    Eigen::Vector3f(0.2f, -0.1f, 0.5f));
    for (int i = 0; i < 50; ++i) points.emplace_back(u(rng), u(rng), u(rng));
    std::vector<Eigen::Vector3f> queries;
    for (int i = 0; i < 3000; ++i) queries.emplace_back(1.5f * u(rng), 1.5f * u(rng), 1.5f * u(rng));  // also outside
    for (int i = 0; i < 500; ++i) queries.push_back(points[rng() % points.size()] + 0.02f * Eigen::Vector3f(u(rng), u(rng), u(rng)));
    queries.emplace_back(50.0f, -40.0f, 3.0f);
    for (double maxDistance : {0.2, 0.05, 1.0}) {
        const auto d = nearestDistances(points, queries, maxDistance);
        ASSERT_EQ(d.size(), queries.size());
        int capped = 0;
        for (size_t i = 0; i < queries.size(); ++i) {
            float best = std::numeric_limits<float>::max();
            for (const auto& p : points) best = std::min(best, (p - queries[i]).squaredNorm());
            const float expected = std::min(std::sqrt(best), float(maxDistance));
            ASSERT_FLOAT_EQ(d[i], expected) << "query " << i << " max distance " << maxDistance;
            capped += d[i] == float(maxDistance);
        }
        EXPECT_GT(capped, 0);  // the cap was exercised
    }
    // No points: everything is at the cap.
    const auto none = nearestDistances({}, queries, 0.2);
    for (float v : none) ASSERT_EQ(v, 0.2f);
}

TEST(Evaluate, IdenticalSurfaceIsPerfect) {
    const auto gt = latticeSquare(0.005);
    const auto rec = sampleByArea(rectangle(0, 1, 0, 1), 0.005, 1);
    const EvalResult r = evaluate(rec, gt);
    EXPECT_EQ(r.gtPoints, gt.size());
    EXPECT_EQ(r.reconstructionSamples, rec.size());
    ASSERT_EQ(r.scores.size(), 3u);
    EXPECT_NEAR(scoreAt(r, 0.01).fscore, 1.0, 1e-3);
    EXPECT_NEAR(scoreAt(r, 0.01).precision, 1.0, 1e-9);  // every sample is within 3.6 mm of a lattice point
    EXPECT_NEAR(scoreAt(r, 0.05).fscore, 1.0, 1e-9);
    // "~0": the floor of point-to-point distances to a 5 mm lattice is ~0.38 x 5 mm.
    EXPECT_LT(r.accuracyMean, 0.0025);
    EXPECT_LT(r.accuracyMedian, 0.0025);
    EXPECT_LT(r.completenessMean, 0.0035);
    // A denser reconstruction sampling brings completeness to ~0 too.
    const EvalResult dense = evaluate(sampleByArea(rectangle(0, 1, 0, 1), 0.001, 1), gt);
    EXPECT_LT(dense.completenessMean, 0.0006);
}

TEST(Evaluate, ShiftedThreeCentimetres) {
    const auto gt = latticeSquare(0.005);
    const auto rec = sampleByArea(rectangle(0, 1, 0, 1, 0.03), 0.005, 1);
    const EvalResult r = evaluate(rec, gt);
    EXPECT_EQ(scoreAt(r, 0.01).precision, 0.0);
    EXPECT_EQ(scoreAt(r, 0.02).precision, 0.0);
    EXPECT_EQ(scoreAt(r, 0.01).recall, 0.0);
    EXPECT_EQ(scoreAt(r, 0.02).fscore, 0.0);
    EXPECT_NEAR(scoreAt(r, 0.05).precision, 1.0, 1e-9);
    EXPECT_NEAR(scoreAt(r, 0.05).recall, 1.0, 1e-9);
    EXPECT_NEAR(r.accuracyMean, 0.03, 0.0005);
    EXPECT_GE(r.accuracyMedian, 0.03 - 1e-6);
    EXPECT_NEAR(r.completenessMean, 0.03, 0.0005);
}

TEST(Evaluate, HalfCoverageHalvesRecall) {
    const auto gt = latticeSquare(0.005);
    const auto rec = sampleByArea(rectangle(0, 0.5, 0, 1), 0.005, 1);
    const EvalResult r = evaluate(rec, gt);
    EXPECT_NEAR(scoreAt(r, 0.01).precision, 1.0, 1e-9);
    // Half the GT plus the 1 cm strip beside the cut.
    EXPECT_NEAR(scoreAt(r, 0.01).recall, 0.51, 0.01);
    EXPECT_NEAR(scoreAt(r, 0.05).recall, 0.55, 0.01);
    EXPECT_NEAR(scoreAt(r, 0.01).fscore, 2 * 0.51 / 1.51, 0.01);
    EXPECT_LT(r.accuracyMean, 0.0025);
    // Completeness is capped at 0.2 m: the missing half (0 to 0.5 m away) contributes (0.02 + 0.3 x 0.2) / 0.5 =
    // 0.16 m on average, the covered half ~0: 0.08 m in all.
    EXPECT_NEAR(r.completenessMean, 0.08, 0.003);
    EvalOptions wide;
    wide.maxDistance = 1.0;
    wide.thresholds = {0.01};
    EXPECT_NEAR(evaluate(rec, gt, wide).completenessMean, 0.125, 0.003);  // uncapped: half of the mean 0.25 of 0..0.5
}

TEST(Evaluate, SeenMaskLimitsRecallNotPrecision) {
    // Only the left half of the GT was seen; the reconstruction covers all of it (correctly).
    const auto gt = latticeSquare(0.005);
    std::vector<bool> seen(gt.size());
    for (size_t i = 0; i < gt.size(); ++i) seen[i] = gt[i].x() < 0.5f;
    const auto rec = sampleByArea(rectangle(0, 1, 0, 1), 0.005, 1);
    const EvalResult r = evaluate(rec, gt, seen);
    EXPECT_EQ(r.gtPoints, gt.size());
    EXPECT_EQ(r.gtPointsSeen, gt.size() / 2);
    EXPECT_NEAR(scoreAt(r, 0.01).recall, 1.0, 1e-9);     // all of the seen half is there
    EXPECT_NEAR(scoreAt(r, 0.01).precision, 1.0, 1e-9);  // and all of the reconstruction is on the true surface
    EXPECT_LT(r.accuracyMean, 0.0025);
    // Against the seen half only, the right half of the reconstruction would count as wrong.
    std::vector<Eigen::Vector3f> seenOnly;
    for (size_t i = 0; i < gt.size(); ++i)
        if (seen[i]) seenOnly.push_back(gt[i]);
    EXPECT_NEAR(scoreAt(evaluate(rec, seenOnly), 0.01).precision, 0.51, 0.01);
    EXPECT_THROW(evaluate(rec, gt, std::vector<bool>(gt.size(), false)), Error);
    EXPECT_THROW(evaluate(rec, gt, std::vector<bool>(3, true)), Error);
}

TEST(Evaluate, BadInputIsAnError) {
    const auto gt = latticeSquare(0.05);
    EXPECT_THROW(evaluate({}, gt), Error);
    EXPECT_THROW(evaluate(gt, {}), Error);
    EvalOptions o;
    o.thresholds = {0.01, 0.3};  // beyond maxDistance 0.2: capped distances cannot tell
    EXPECT_THROW(evaluate(gt, gt, o), Error);
    o.thresholds = {0.0};
    EXPECT_THROW(evaluate(gt, gt, o), Error);
    std::vector<Eigen::Vector3f> nan = gt;
    nan[3].x() = std::nanf("");
    EXPECT_THROW(evaluate(nan, gt), Error);
}

namespace {

// A sphere of 0.3 m, 1.5 m in front of the first camera of the synthetic path, rendered in one small frame.
struct SphereSequence {
    fs::path dir;
    Eigen::Vector3d eye, forward, centre;
    double radius = 0.3;
};

const SphereSequence& sphereSequence() {
    static SphereSequence s = [] {
        SphereSequence q;
        q.dir = test::makeTempDir("eval_sphere");
        const Pose pose = synth::cameraPath(1)[0];
        q.eye = pose.topRightCorner<3, 1>();
        q.forward = pose.block<3, 1>(0, 2);
        q.centre = q.eye + 1.5 * q.forward;
        synth::SequenceOptions o;
        o.frames = 1;
        o.width = 80;
        o.height = 60;
        o.intrinsics = synth::kinectIntrinsics(80, 60);
        o.gtPointSpacing = 0.01;
        synth::writeTumSequence(q.dir, synth::SyntheticScene::singleSphere(q.centre, q.radius), o);
        return q;
    }();
    return s;
}

}  // namespace

TEST(SeenMask, SphereSeenFromOneSide) {
    const SphereSequence& s = sphereSequence();
    const auto dataset = Dataset::open(s.dir);
    ASSERT_EQ(dataset->size(), 1u);
    const Mesh gt = readPly(s.dir / "gt_points.ply");
    ASSERT_GT(gt.positions.size(), 3000u);  // 4 pi 0.09 / 1e-4 ~ 11000
    std::vector<std::string> warnings;
    const std::vector<bool> seen = seenMask(gt.positions, *dataset, 1, 0.02, &warnings);
    ASSERT_EQ(seen.size(), gt.positions.size());
    EXPECT_TRUE(warnings.empty());

    // Known points: the GT points nearest to the pole facing the camera, 40 degrees off it, the far pole
    // and a point of the far side 50 degrees off it.
    const Eigen::Vector3d side = s.forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    auto nearestGt = [&](const Eigen::Vector3d& direction) {
        const Eigen::Vector3f target = (s.centre + s.radius * direction.normalized()).cast<float>();
        size_t best = 0;
        for (size_t i = 0; i < gt.positions.size(); ++i)
            if ((gt.positions[i] - target).squaredNorm() < (gt.positions[best] - target).squaredNorm()) best = i;
        return best;
    };
    const double d40 = 40 * M_PI / 180, d50 = 50 * M_PI / 180;
    EXPECT_TRUE(seen[nearestGt(-s.forward)]);
    EXPECT_TRUE(seen[nearestGt(-std::cos(d40) * s.forward + std::sin(d40) * side)]);
    EXPECT_TRUE(seen[nearestGt(-std::cos(d40) * s.forward - std::sin(d40) * Eigen::Vector3d::UnitZ())]);
    EXPECT_FALSE(seen[nearestGt(s.forward)]);
    EXPECT_FALSE(seen[nearestGt(std::cos(d50) * s.forward + std::sin(d50) * side)]);

    // All of it: the part facing the camera squarely is seen, none of the part facing away.
    size_t facing = 0, facingSeen = 0, away = 0, awaySeen = 0, total = 0;
    for (size_t i = 0; i < gt.positions.size(); ++i) {
        const Eigen::Vector3d p = gt.positions[i].cast<double>();
        const double c = (p - s.centre).normalized().dot((s.eye - p).normalized());
        if (c > 0.7) facing++, facingSeen += seen[i];
        if (c < -0.2) away++, awaySeen += seen[i];
        total += seen[i];
    }
    EXPECT_GT(facing, 500u);
    EXPECT_EQ(facingSeen, facing);
    EXPECT_GT(away, 3000u);
    EXPECT_EQ(awaySeen, 0u);
    // The cap visible from 1.5 m is (1 - r / D) / 2 = 40 % of the sphere; a little less at grazing angles.
    const double share = double(total) / double(gt.positions.size());
    EXPECT_GT(share, 0.3);
    EXPECT_LT(share, 0.42);

    // A tolerance of 0 still accepts 3 quantisation steps (0.6 mm): most of the facing part, not all.
    const std::vector<bool> strict = seenMask(gt.positions, *dataset, 1, 0.0);
    const size_t strictCount = std::count(strict.begin(), strict.end(), true);
    EXPECT_GT(strictCount, 0u);
    EXPECT_LT(strictCount, total);
}

namespace {

using test::CliRun;
using test::readText;
using test::runCli;

bool cliHasEval() {
    static const bool has = runCli("eval --help").exitCode == 0;
    return has;
}

}  // namespace

TEST(EvalCli, ScoresAMeshAndWritesJson) {
    if (!cliHasEval()) GTEST_SKIP() << VKMESH_CLI << " has no `eval` command yet (host/commands.h must list it)";
    const fs::path dir = test::makeTempDir("eval_cli_plane");
    Mesh gt;
    gt.positions = latticeSquare(0.005);
    writePly(dir / "gt.ply", gt);
    writePly(dir / "mesh.ply", rectangle(0, 0.5, 0, 1));
    const CliRun r = runCli("eval " + (dir / "mesh.ply").string() + " --gt " + (dir / "gt.ply").string() +
                            " --thresholds 0.01,0.05 --json " + (dir / "out.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("F-score"), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(readText(dir / "out.json"));
    EXPECT_EQ(j["gt_points"], 40000);
    EXPECT_EQ(j["gt_points_seen"], 40000);
    EXPECT_NEAR(j["reconstruction_samples"].get<double>(), 20000, 100);
    ASSERT_EQ(j["scores"].size(), 2u);
    EXPECT_EQ(j["scores"][0]["threshold"], 0.01);
    EXPECT_NEAR(j["scores"][0]["precision"].get<double>(), 1.0, 1e-9);
    EXPECT_NEAR(j["scores"][0]["recall"].get<double>(), 0.51, 0.01);
    EXPECT_TRUE(j["scores"][1].contains("fscore"));
    for (const char* key : {"accuracy_mean", "accuracy_median", "completeness_mean", "completeness_median"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_NEAR(j["completeness_mean"].get<double>(), 0.08, 0.003);
    fs::remove_all(dir);
}

TEST(EvalCli, DatasetRestrictsTheGroundTruth) {
    if (!cliHasEval()) GTEST_SKIP() << VKMESH_CLI << " has no `eval` command yet (host/commands.h must list it)";
    const SphereSequence& s = sphereSequence();
    const fs::path out = test::makeTempDir("eval_cli_seen");
    // The GT cloud itself as the "reconstruction": all the seen GT is found, so recall is 1.
    const std::string gt = (s.dir / "gt_points.ply").string();
    const CliRun r = runCli("eval " + gt + " --gt " + gt + " --dataset " + s.dir.string() + " --json " +
                            (out / "out.json").string() + " --write-seen " + (out / "seen.ply").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(readText(out / "out.json"));
    const size_t total = j["gt_points"], seen = j["gt_points_seen"];
    EXPECT_GT(seen, total * 3 / 10);
    EXPECT_LT(seen, total / 2);
    EXPECT_EQ(readPly(out / "seen.ply").positions.size(), seen);
    EXPECT_EQ(j["scores"][0]["recall"], 1.0);
    EXPECT_EQ(j["scores"][0]["precision"], 1.0);  // against all GT points: the cloud is the GT
    EXPECT_EQ(j["dataset"]["frames_evaluated"], 1);
    // Precision against the seen part only: the far side of the sphere counts as wrong.
    const CliRun seenOnly = runCli("eval " + gt + " --gt " + gt + " --dataset " + s.dir.string() +
                                   " --precision-against seen --json " + (out / "seen.json").string());
    ASSERT_EQ(seenOnly.exitCode, 0) << seenOnly.err;
    const auto k = nlohmann::json::parse(readText(out / "seen.json"));
    EXPECT_LT(k["scores"][0]["precision"].get<double>(), 0.6);
    EXPECT_EQ(k["scores"][0]["recall"], 1.0);
    fs::remove_all(out);
}

TEST(EvalCli, BadInputNamesTheFile) {
    if (!cliHasEval()) GTEST_SKIP() << VKMESH_CLI << " has no `eval` command yet (host/commands.h must list it)";
    const fs::path dir = test::makeTempDir("eval_cli_bad");
    writePly(dir / "mesh.ply", rectangle(0, 1, 0, 1));
    writePly(dir / "empty.ply", Mesh{});
    Mesh flat = rectangle(0, 1, 0, 1);
    for (auto& p : flat.positions) p = Eigen::Vector3f(0.5f, 0.5f, 0.0f);  // every triangle degenerate
    writePly(dir / "flat.ply", flat);

    CliRun r = runCli("eval /nonexistent/vkmesh_mesh.ply --gt " + (dir / "mesh.ply").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("/nonexistent/vkmesh_mesh.ply"), std::string::npos) << r.err;
    r = runCli("eval " + (dir / "mesh.ply").string() + " --gt " + (dir / "empty.ply").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find((dir / "empty.ply").string()), std::string::npos) << r.err;
    r = runCli("eval " + (dir / "empty.ply").string() + " --gt " + (dir / "mesh.ply").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find((dir / "empty.ply").string()), std::string::npos) << r.err;
    r = runCli("eval " + (dir / "flat.ply").string() + " --gt " + (dir / "mesh.ply").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find((dir / "flat.ply").string()), std::string::npos) << r.err;
    r = runCli("eval " + (dir / "mesh.ply").string() + " --gt " + (dir / "mesh.ply").string() + " --thresholds 0.01,abc");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("abc"), std::string::npos) << r.err;
    fs::remove_all(dir);
}

// ------------------------------------------------------------------------------------------ colour

TEST(ColorError, KnownPairsGiveKnownMaeAndPsnr) {
    ColorErrorSum sum;
    EXPECT_EQ(sum.result().pairs, 0u);
    sum.add({10, 20, 30}, {0, 20, 40});
    sum.add({0, 0, 0}, {0, 0, 0});
    const ColorError e = sum.result();
    EXPECT_EQ(e.pairs, 2u);
    EXPECT_DOUBLE_EQ(e.mae[0], 5.0);
    EXPECT_DOUBLE_EQ(e.mae[1], 0.0);
    EXPECT_DOUBLE_EQ(e.mae[2], 5.0);
    EXPECT_NEAR(e.maeMean, 10.0 / 3, 1e-12);
    // MSE over all channels: (100 + 0 + 100 + 0 + 0 + 0) / 6.
    EXPECT_NEAR(e.psnr, 10 * std::log10(255.0 * 255.0 / (200.0 / 6)), 1e-9);
    ColorErrorSum same;
    same.add({1, 2, 3}, {1, 2, 3});
    EXPECT_TRUE(std::isinf(same.result().psnr));
    // The worst case: 255 apart everywhere is 0 dB.
    ColorErrorSum worst;
    worst.add({255, 255, 255}, {0, 0, 0});
    EXPECT_NEAR(worst.result().psnr, 0.0, 1e-12);
    sum.merge(worst);
    EXPECT_EQ(sum.result().pairs, 3u);
    EXPECT_NEAR(sum.result().mae[1], 255.0 / 3, 1e-12);
}

TEST(ColorError, AgainstGtTakesTheNearestVertexOfEachSeenPoint) {
    // Mesh vertices on a 1 cm lattice, red = 10 * column; GT points 2 mm off each vertex, red = 10 * column + 4.
    Mesh mesh;
    std::vector<Eigen::Vector3f> gt;
    std::vector<std::array<uint8_t, 3>> gtColors;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) {
            mesh.positions.emplace_back(0.01f * i, 0.01f * j, 0.0f);
            mesh.colors.push_back({uint8_t(10 * i), 100, 50});
            gt.emplace_back(0.01f * i + 0.002f, 0.01f * j, 0.0f);
            gtColors.push_back({uint8_t(10 * i + 4), 100, 50});
        }
    // A GT point far from the mesh (a completeness matter) with a very different colour: left out.
    gt.emplace_back(1.0f, 1.0f, 1.0f);
    gtColors.push_back({255, 255, 255});
    ColorError e = colorErrorAgainstGt(mesh, gt, gtColors, {}, 0.02);
    EXPECT_EQ(e.pairs, 100u);
    EXPECT_DOUBLE_EQ(e.mae[0], 4.0);
    EXPECT_DOUBLE_EQ(e.mae[1], 0.0);
    EXPECT_NEAR(e.psnr, 10 * std::log10(255.0 * 255.0 / (16.0 / 3)), 1e-9);
    // A seen mask restricts the GT points: only the first column (10 points) is seen.
    std::vector<bool> seen(gt.size(), false);
    for (int j = 0; j < 10; ++j) seen[j] = true;
    gtColors[0] = {0, 100, 60};  // one of them 10 off in blue, and 0 in red
    e = colorErrorAgainstGt(mesh, gt, gtColors, seen, 0.02);
    EXPECT_EQ(e.pairs, 10u);
    EXPECT_DOUBLE_EQ(e.mae[0], 4.0 * 9 / 10);
    EXPECT_DOUBLE_EQ(e.mae[2], 1.0);
    // Missing or mismatched colours are errors.
    Mesh grey = mesh;
    grey.colors.clear();
    EXPECT_THROW(colorErrorAgainstGt(grey, gt, gtColors, {}, 0.02), Error);
    gtColors.pop_back();
    EXPECT_THROW(colorErrorAgainstGt(mesh, gt, gtColors, {}, 0.02), Error);
}

TEST(ColorError, AgainstFramesComparesTheVerticesEachFrameSees) {
    // The sphere sequence's GT cloud as the "mesh", coloured 10 too red where the frame sees it and black on
    // the far side: the far side must not count (it is behind the visible surface).
    const SphereSequence& s = sphereSequence();
    const auto dataset = Dataset::open(s.dir);
    ASSERT_TRUE(dataset->hasColor());
    Mesh mesh = readPly(s.dir / "gt_points.ply");
    ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
    const std::vector<bool> seen = seenMask(mesh.positions, *dataset, 1, 0.03);
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        mesh.colors[i] = seen[i] ? std::array<uint8_t, 3>{190, 180, 180} : std::array<uint8_t, 3>{0, 0, 0};
    std::vector<std::string> warnings;
    size_t framesUsed = 0;
    const ColorError e = colorErrorAgainstFrames(mesh, *dataset, 1, 0.03, &warnings, &framesUsed);
    EXPECT_TRUE(warnings.empty());
    EXPECT_EQ(framesUsed, 1u);
    EXPECT_GT(e.pairs, 500u);  // the 80x60 image sees ~1000 of the sphere's points
    EXPECT_NEAR(e.mae[0], 10.0, 0.5);  // the sphere is uniform grey 180
    EXPECT_LT(e.mae[1], 0.5);
    EXPECT_LT(e.mae[2], 0.5);
    EXPECT_THROW(colorErrorAgainstFrames(mesh, *dataset, 0), Error);
    mesh.colors.clear();
    EXPECT_THROW(colorErrorAgainstFrames(mesh, *dataset, 1), Error);
}

TEST(EvalCli, ColourAgainstGtAndAgainstFrames) {
    if (!cliHasEval()) GTEST_SKIP() << VKMESH_CLI << " has no `eval` command yet (host/commands.h must list it)";
    const SphereSequence& s = sphereSequence();
    const fs::path out = test::makeTempDir("eval_cli_color");
    const std::string gt = (s.dir / "gt_points.ply").string();
    Mesh mesh = readPly(gt);
    for (auto& c : mesh.colors) c[1] = uint8_t(c[1] - 20);  // 20 less green everywhere
    writePly(out / "mesh.ply", mesh);
    const std::string meshPath = (out / "mesh.ply").string();
    CliRun r = runCli("eval " + meshPath + " --gt " + gt + " --dataset " + s.dir.string() + " --color-every 1 --json " +
                      (out / "out.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("colour vs GT"), std::string::npos) << r.out;
    auto j = nlohmann::json::parse(readText(out / "out.json"));
    EXPECT_EQ(j["color_vs_gt"]["pairs"], j["gt_points_seen"]);
    EXPECT_DOUBLE_EQ(j["color_vs_gt"]["mae_green"].get<double>(), 20.0);
    EXPECT_DOUBLE_EQ(j["color_vs_gt"]["mae_red"].get<double>(), 0.0);
    EXPECT_NEAR(j["color_vs_gt"]["psnr"].get<double>(), 10 * std::log10(255.0 * 255.0 / (400.0 / 3)), 1e-9);
    EXPECT_GT(j["color_vs_frames"]["pairs"].get<size_t>(), 500u);
    EXPECT_NEAR(j["color_vs_frames"]["mae_green"].get<double>(), 20.0, 0.5);
    EXPECT_EQ(j["color_vs_frames"]["frames_used"], 1);
    EXPECT_TRUE(j.contains("accuracy_mean"));  // the geometry keys stay

    // Real data without GT: colour only.
    r = runCli("eval " + meshPath + " --dataset " + s.dir.string() + " --color-every 1 --json " + (out / "c.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    j = nlohmann::json::parse(readText(out / "c.json"));
    EXPECT_NEAR(j["color_vs_frames"]["mae_green"].get<double>(), 20.0, 0.5);
    EXPECT_TRUE(j["color_vs_gt"].is_null());
    // Neither --gt nor --color-every: an error that says what to give.
    r = runCli("eval " + meshPath + " --dataset " + s.dir.string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--gt"), std::string::npos) << r.err;
    // A mesh without colours has no colour keys but still its geometry.
    mesh.colors.clear();
    writePly(out / "grey.ply", mesh);
    r = runCli("eval " + (out / "grey.ply").string() + " --gt " + gt + " --json " + (out / "g.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    j = nlohmann::json::parse(readText(out / "g.json"));
    EXPECT_TRUE(j["color_vs_gt"].is_null());
    fs::remove_all(out);
}
