// `vkmesh eval`: quality of a mesh (or point cloud) against ground-truth surface points.
//   vkmesh eval MESH.ply --gt GT.ply [--dataset DIR [--frame-stride K]] [--spacing 0.005]
//               [--thresholds 0.01,0.02,0.05] [--max-distance 0.2] [--json out.json]
// Prints accuracy, completeness and precision / recall / F-score per threshold; see src/eval/evaluate.h.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "core/types.h"
#include "eval/evaluate.h"
#include "io/dataset.h"
#include "io/ply.h"

namespace vkmesh::cli {
namespace {

using json = nlohmann::json;

struct EvalArgs {
    std::string mesh;
    std::string gt;
    std::string dataset;
    size_t frameStride = 1;
    size_t frames = 0;
    float maxDepth = 4.0f;
    std::string intrinsics;
    double depthScale = 0;
    double seenTolerance = 0.02;
    double spacing = 0.005;
    std::string thresholds = "0.01,0.02,0.05";
    double maxDistance = 0.2;
    uint32_t seed = 1;
    std::string jsonPath;
    std::string seenPath;
    std::string precisionAgainst = "all";
};

std::vector<double> parseThresholds(const std::string& text) {
    std::vector<double> values;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        double v = 0;
        try {
            v = std::stod(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
        if (item.empty() || used != item.size())
            throw Error("--thresholds '" + text + "': '" + item + "' is not a number (expected e.g. 0.01,0.02,0.05)");
        values.push_back(v);
    }
    if (values.empty()) throw Error("--thresholds '" + text + "': no threshold given");
    return values;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Points of a PLY file as evaluated: a mesh sampled by area, a point cloud as it is, non-finite points
// dropped (with a warning). Throws Error naming the file when nothing is left.
std::vector<Eigen::Vector3f> pointsOf(const std::string& path, const Mesh& mesh, const char* role, double spacing,
                                      uint32_t seed, std::vector<std::string>& warnings) {
    std::vector<Eigen::Vector3f> points;
    try {
        points = eval::sampleByArea(mesh, spacing, seed);
    } catch (const Error& e) {
        throw Error(std::string(role) + " '" + path + "': " + e.what());
    }
    const size_t before = points.size();
    std::erase_if(points, [](const Eigen::Vector3f& p) { return !p.allFinite(); });
    if (points.size() != before)
        warnings.push_back(std::string(role) + " '" + path + "': " + std::to_string(before - points.size()) +
                           " non-finite points ignored");
    if (points.empty()) {
        if (mesh.triangles.empty())
            throw Error(std::string(role) + " '" + path + "' has no points (" + std::to_string(mesh.positions.size()) +
                        " vertices, none finite)");
        throw Error(std::string(role) + " '" + path + "' has no surface to sample (" +
                    std::to_string(mesh.positions.size()) + " vertices, " + std::to_string(mesh.triangles.size()) +
                    " triangles, all degenerate or non-finite)");
    }
    return points;
}

int runEval(const EvalArgs& args) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::string> warnings;
    eval::EvalOptions options;
    options.thresholds = parseThresholds(args.thresholds);
    options.sampleSpacing = args.spacing;
    options.seed = args.seed;
    options.maxDistance = args.maxDistance;
    if (!(std::isfinite(options.maxDistance) && options.maxDistance > 0))
        throw Error("--max-distance " + std::to_string(options.maxDistance) + " must be positive");
    for (double t : options.thresholds)
        if (!(std::isfinite(t) && t > 0 && t <= options.maxDistance))
            throw Error("--thresholds: " + std::to_string(t) + " must be in (0, --max-distance " +
                        std::to_string(options.maxDistance) + "]");
    if (!(std::isfinite(args.spacing) && args.spacing > 0))
        throw Error("--spacing " + std::to_string(args.spacing) + " must be positive");

    // Inputs. An empty mesh or GT file is an error naming the file.
    auto t0 = std::chrono::steady_clock::now();
    const Mesh mesh = readPly(args.mesh);
    if (mesh.positions.empty()) throw Error("mesh '" + args.mesh + "' is empty (no vertices)");
    const Mesh gtMesh = readPly(args.gt);
    if (gtMesh.positions.empty()) throw Error("ground truth '" + args.gt + "' has no points");
    const double readSeconds = secondsSince(t0);

    t0 = std::chrono::steady_clock::now();
    const std::vector<Eigen::Vector3f> samples =
        pointsOf(args.mesh, mesh, "mesh", options.sampleSpacing, options.seed, warnings);
    // A GT given as a mesh is sampled the same way (another seed, so the two never share points).
    std::vector<Eigen::Vector3f> gtAll = pointsOf(args.gt, gtMesh, "ground truth", options.sampleSpacing,
                                                  options.seed + 1, warnings);
    const double sampleSeconds = secondsSince(t0);

    // The GT surface the sequence saw.
    t0 = std::chrono::steady_clock::now();
    std::vector<bool> seen;
    size_t seenCount = gtAll.size();
    json datasetJson = nullptr;
    if (!args.dataset.empty()) {
        DatasetOptions dopts;
        if (!args.intrinsics.empty()) dopts.intrinsics = parseIntrinsics(args.intrinsics);
        if (args.depthScale > 0) dopts.depthScale = args.depthScale;
        dopts.maxDepth = args.maxDepth;
        dopts.maxFrames = args.frames;
        const auto dataset = Dataset::open(args.dataset, dopts);
        for (const auto& w : dataset->warnings()) warnings.push_back(w);
        if (dataset->size() == 0) throw Error("no usable frame in " + args.dataset);
        const size_t stride = std::max<size_t>(args.frameStride, 1);
        seen = eval::seenMask(gtAll, *dataset, stride, args.seenTolerance, &warnings);
        seenCount = size_t(std::count(seen.begin(), seen.end(), true));
        const size_t framesUsed = (dataset->size() + stride - 1) / stride;
        if (seenCount == 0)
            throw Error("none of the " + std::to_string(gtAll.size()) + " ground-truth points of '" + args.gt +
                        "' was seen in the " + std::to_string(framesUsed) + " frames of '" + args.dataset +
                        "' (do the GT and the dataset's poses share one coordinate frame?)");
        datasetJson = {{"path", std::filesystem::absolute(args.dataset).string()},
                       {"kind", toString(dataset->kind())},
                       {"frames", dataset->size()},
                       {"frames_evaluated", framesUsed},
                       {"frame_stride", stride},
                       {"max_depth", args.maxDepth},
                       {"seen_tolerance", std::max(args.seenTolerance, 3.0 / dataset->depthScale())}};
        if (!args.seenPath.empty()) {
            Mesh seenCloud;
            for (size_t i = 0; i < gtAll.size(); ++i)
                if (seen[i]) seenCloud.positions.push_back(gtAll[i]);
            writePly(args.seenPath, seenCloud);
        }
    }
    const double seenSeconds = secondsSince(t0);

    // Completeness and recall of the seen GT; accuracy and precision against all of it (or, with
    // --precision-against seen, against the seen part only).
    t0 = std::chrono::steady_clock::now();
    eval::EvalResult result;
    if (seen.empty()) {
        result = eval::evaluate(samples, gtAll, options);
    } else if (args.precisionAgainst == "all") {
        result = eval::evaluate(samples, gtAll, seen, options);
    } else {
        std::vector<Eigen::Vector3f> gtSeen;
        for (size_t i = 0; i < gtAll.size(); ++i)
            if (seen[i]) gtSeen.push_back(gtAll[i]);
        result = eval::evaluate(samples, gtSeen, options);
    }
    result.gtPoints = gtAll.size();
    result.gtPointsSeen = seenCount;
    const double distanceSeconds = secondsSince(t0);

    json j;
    j["mesh"] = {{"path", args.mesh}, {"vertices", mesh.positions.size()}, {"triangles", mesh.triangles.size()}};
    j["gt"] = {{"path", args.gt}, {"vertices", gtMesh.positions.size()}, {"triangles", gtMesh.triangles.size()}};
    j["dataset"] = datasetJson;
    j["options"] = {{"sample_spacing", options.sampleSpacing},
                    {"seed", options.seed},
                    {"max_distance", options.maxDistance},
                    {"thresholds", options.thresholds},
                    {"precision_against", seen.empty() || args.precisionAgainst == "all" ? "all GT points" : "seen GT points"},
                    {"recall_of", seen.empty() ? "all GT points" : "seen GT points"}};
    j["reconstruction_samples"] = result.reconstructionSamples;
    j["gt_points"] = result.gtPoints;
    j["gt_points_seen"] = result.gtPointsSeen;
    j["accuracy_mean"] = result.accuracyMean;
    j["accuracy_median"] = result.accuracyMedian;
    j["completeness_mean"] = result.completenessMean;
    j["completeness_median"] = result.completenessMedian;
    j["scores"] = json::array();
    for (const auto& s : result.scores)
        j["scores"].push_back({{"threshold", s.threshold}, {"precision", s.precision}, {"recall", s.recall},
                               {"fscore", s.fscore}});
    j["seconds"] = {{"read", readSeconds},
                    {"sample", sampleSeconds},
                    {"seen_mask", seenSeconds},
                    {"distances", distanceSeconds},
                    {"total", secondsSince(start)}};
    j["warnings"] = warnings;
    if (!args.jsonPath.empty()) {
        std::ofstream file(args.jsonPath);
        if (!file) throw Error("cannot write '" + args.jsonPath + "'");
        file << j.dump(2) << "\n";
        if (!file) throw Error("cannot write '" + args.jsonPath + "' (disk full?)");
    }

    for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
    std::printf("vkmesh eval: %s (%zu samples) vs %s (%zu GT points, %zu seen%s)\n", args.mesh.c_str(),
                result.reconstructionSamples, args.gt.c_str(), result.gtPoints, result.gtPointsSeen,
                args.dataset.empty() ? ", no --dataset: all" : "");
    const bool precisionOfSeen = !seen.empty() && args.precisionAgainst == "seen";
    std::printf("  accuracy      mean %7.2f mm  median %7.2f mm   (reconstruction -> %s GT, capped at %.0f mm)\n",
                1000 * result.accuracyMean, 1000 * result.accuracyMedian, precisionOfSeen ? "seen" : "all",
                1000 * options.maxDistance);
    std::printf("  completeness  mean %7.2f mm  median %7.2f mm   (%s GT -> reconstruction)\n",
                1000 * result.completenessMean, 1000 * result.completenessMedian, seen.empty() ? "all" : "seen");
    std::printf("  %9s  %9s  %7s  %7s\n", "threshold", "precision", "recall", "F-score");
    for (const auto& s : result.scores)
        std::printf("  %6.1f mm  %9.4f  %7.4f  %7.4f\n", 1000 * s.threshold, s.precision, s.recall, s.fscore);
    std::fflush(stdout);
    return 0;
}

}  // namespace

Run addEvalCommand(CLI::App& app) {
    auto args = std::make_shared<EvalArgs>();
    CLI::App* cmd = app.add_subcommand(
        "eval", "accuracy, completeness, precision/recall/F-score of a mesh against ground-truth points");
    cmd->add_option("MESH", args->mesh, "reconstruction: a PLY mesh (sampled by area) or point cloud (used as is)")
        ->required();
    cmd->add_option("--gt", args->gt, "ground truth PLY: points (e.g. a synthetic sequence's gt_points.ply) or a mesh")
        ->required();
    cmd->add_option("--dataset", args->dataset,
                    "restrict the GT to what this sequence saw (the folder given to fuse; same layouts)");
    cmd->add_option("--frame-stride", args->frameStride, "with --dataset: check every Kth frame only (faster)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--frames", args->frames, "with --dataset: the first N frames only, as fuse --frames (0 = all)");
    cmd->add_option("--max-depth", args->maxDepth, "with --dataset: ignore depth beyond M metres, as fuse (0 = no limit)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--intrinsics", args->intrinsics, "with --dataset: override the camera: fx,fy,cx,cy");
    cmd->add_option("--depth-scale", args->depthScale, "with --dataset: raw depth units per metre")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--seen-tolerance", args->seenTolerance,
                    "with --dataset: a GT point is seen where |its depth - measured depth| < this (metres)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--write-seen", args->seenPath, "with --dataset: write the seen GT points to this PLY");
    cmd->add_option("--precision-against", args->precisionAgainst,
                    "with --dataset: accuracy/precision against all GT points (default) or the seen ones only; "
                    "completeness/recall are always of the seen ones")
        ->check(CLI::IsMember({"all", "seen"}));
    cmd->add_option("--spacing", args->spacing, "metres between area samples of the mesh");
    cmd->add_option("--thresholds", args->thresholds, "distance thresholds in metres, comma-separated");
    cmd->add_option("--max-distance", args->maxDistance, "distances are capped here (metres) for means and medians");
    cmd->add_option("--seed", args->seed, "seed of the area sampling");
    cmd->add_option("--json", args->jsonPath, "write every number as JSON");
    return [args] { return runEval(*args); };
}

}  // namespace vkmesh::cli
