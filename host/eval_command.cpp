// `vkmesh eval`: quality of a mesh (or point cloud) against ground-truth surface points.
//   vkmesh eval MESH.ply --gt GT.ply [--dataset DIR [--frame-stride K]] [--spacing 0.005]
//               [--thresholds 0.01,0.02,0.05] [--max-distance 0.2] [--json out.json]
//   vkmesh eval MESH.ply --dataset DIR --color-every K      (colour only, real data without GT)
// Prints accuracy, completeness and precision / recall / F-score per threshold; see src/eval/evaluate.h.
// Colour, when the mesh has vertex colours: against the GT points' colours when they have some (JSON
// "color_vs_gt"), and against every Kth frame's colour image with --color-every K ("color_vs_frames").
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
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
    size_t colorEvery = 0;         // with --dataset: compare with every Kth frame's colour image; 0 = not
    double colorDistance = 0.02;   // colour vs GT: GT points farther from every mesh vertex are left out
    double colorTolerance = 0.03;  // colour vs frames: a vertex is seen where |its depth - measured| < this
};

// Writes the --json report; an unwritable file is an error naming it.
void writeJson(const std::string& path, const json& j) {
    std::ofstream file(path);
    if (!file) throw Error("cannot write '" + path + "'");
    file << j.dump(2) << "\n";
    if (!file) throw Error("cannot write '" + path + "' (disk full?)");
}

json colorJson(const eval::ColorError& e) {
    // PSNR is +infinity for identical colours: nlohmann writes null, which the text output says as "inf".
    return {{"pairs", e.pairs},        {"mae_red", e.mae[0]}, {"mae_green", e.mae[1]},
            {"mae_blue", e.mae[2]},    {"mae_mean", e.maeMean}, {"psnr", e.psnr}};
}

void printColor(const char* what, const eval::ColorError& e) {
    std::printf("  colour %-10s MAE r %6.2f g %6.2f b %6.2f mean %6.2f (0-255)  PSNR %6.2f dB  (%zu pairs)\n", what,
                e.mae[0], e.mae[1], e.mae[2], e.maeMean, e.psnr, e.pairs);
}

// Colour against a dataset's colour images, every Kth frame; null when not asked for.
json colorVsFrames(const EvalArgs& args, const Mesh& mesh, const Dataset& dataset, std::vector<std::string>& warnings,
                   std::optional<eval::ColorError>& out) {
    if (args.colorEvery == 0) return nullptr;
    if (mesh.colors.empty()) {
        warnings.push_back("--color-every: mesh '" + args.mesh + "' has no vertex colours; no colour error");
        return nullptr;
    }
    if (!dataset.hasColor()) {
        warnings.push_back("--color-every: dataset '" + args.dataset + "' has no colour images; no colour error");
        return nullptr;
    }
    size_t used = 0;
    out = eval::colorErrorAgainstFrames(mesh, dataset, args.colorEvery, args.colorTolerance, &warnings, &used);
    json j = colorJson(*out);
    j["every"] = args.colorEvery;
    j["frames_used"] = used;
    j["depth_tolerance"] = args.colorTolerance;
    j["definition"] = "mesh vertices seen by every Kth frame (inside the image, |camera depth - depth image| < "
                      "depth_tolerance) vs that frame's colour pixel";
    return j;
}

std::unique_ptr<Dataset> openDataset(const EvalArgs& args) {
    DatasetOptions dopts;
    if (!args.intrinsics.empty()) dopts.intrinsics = parseIntrinsics(args.intrinsics);
    if (args.depthScale > 0) dopts.depthScale = args.depthScale;
    dopts.maxDepth = args.maxDepth;
    dopts.maxFrames = args.frames;
    return Dataset::open(args.dataset, dopts);
}

// `vkmesh eval MESH --dataset D --color-every K` without --gt: the colour error only.
int runColorOnly(const EvalArgs& args) {
    std::vector<std::string> warnings;
    const Mesh mesh = readPly(args.mesh);
    if (mesh.positions.empty()) throw Error("mesh '" + args.mesh + "' is empty (no vertices)");
    if (mesh.colors.empty()) throw Error("mesh '" + args.mesh + "' has no vertex colours (red, green, blue) to evaluate");
    const auto dataset = openDataset(args);
    for (const auto& w : dataset->warnings()) warnings.push_back(w);
    if (!dataset->hasColor()) throw Error("dataset '" + args.dataset + "' has no colour images to compare with");
    std::optional<eval::ColorError> frames;
    json j;
    j["mesh"] = {{"path", args.mesh}, {"vertices", mesh.positions.size()}, {"triangles", mesh.triangles.size()}};
    j["dataset"] = {{"path", std::filesystem::absolute(args.dataset).string()},
                    {"kind", toString(dataset->kind())},
                    {"frames", dataset->size()}};
    j["color_vs_gt"] = nullptr;
    j["color_vs_frames"] = colorVsFrames(args, mesh, *dataset, warnings, frames);
    j["warnings"] = warnings;
    if (!args.jsonPath.empty()) writeJson(args.jsonPath, j);
    for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
    std::printf("vkmesh eval: %s vs the colour images of %s\n", args.mesh.c_str(), args.dataset.c_str());
    if (frames) printColor("vs frames", *frames);
    std::fflush(stdout);
    return 0;
}

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
    if (args.gt.empty()) {
        if (args.dataset.empty() || args.colorEvery == 0)
            throw Error("--gt is required (without it: --dataset DIR --color-every K for the colour error alone)");
        return runColorOnly(args);
    }
    if (!(std::isfinite(args.colorDistance) && args.colorDistance > 0))
        throw Error("--color-distance " + std::to_string(args.colorDistance) + " must be positive");
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
    json colorFramesJson = nullptr;
    std::optional<eval::ColorError> colorFrames;
    if (!args.dataset.empty()) {
        const auto dataset = openDataset(args);
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
        colorFramesJson = colorVsFrames(args, mesh, *dataset, warnings, colorFrames);
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

    // Colour against the GT points' own colours, when both sides have colour. A GT given as a point cloud
    // is used point for point (gtAll is its finite points, in order); a GT mesh's area samples carry none.
    json colorGtJson = nullptr;
    std::optional<eval::ColorError> colorGt;
    if (!mesh.colors.empty() && !gtMesh.colors.empty() && gtMesh.triangles.empty()) {
        std::vector<std::array<uint8_t, 3>> gtColors;
        for (size_t i = 0; i < gtMesh.positions.size(); ++i)
            if (gtMesh.positions[i].allFinite()) gtColors.push_back(gtMesh.colors[i]);
        colorGt = eval::colorErrorAgainstGt(mesh, gtAll, gtColors, seen, args.colorDistance);
        colorGtJson = colorJson(*colorGt);
        colorGtJson["max_distance"] = args.colorDistance;
        colorGtJson["definition"] = std::string(seen.empty() ? "every" : "every seen") +
                                    " GT point with a mesh vertex within max_distance: the nearest vertex's colour "
                                    "vs the point's";
    } else if (!mesh.colors.empty() && !gtMesh.colors.empty()) {
        warnings.push_back("ground truth '" + args.gt + "' is a mesh: its colours are not compared (give GT points)");
    }

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
    j["color_vs_gt"] = colorGtJson;
    j["color_vs_frames"] = colorFramesJson;
    j["warnings"] = warnings;
    if (!args.jsonPath.empty()) writeJson(args.jsonPath, j);

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
    if (colorGt) printColor("vs GT", *colorGt);
    if (colorFrames) printColor("vs frames", *colorFrames);
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
    cmd->add_option("--gt", args->gt,
                    "ground truth PLY: points (e.g. a synthetic sequence's gt_points.ply) or a mesh; required "
                    "unless --dataset with --color-every (colour only)");
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
    cmd->add_option("--color-every", args->colorEvery,
                    "with --dataset: colour error of the mesh's vertex colours against every Kth frame's colour image")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--color-tolerance", args->colorTolerance,
                    "with --color-every: a vertex is seen by a frame where |its depth - measured depth| < this (metres)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--color-distance", args->colorDistance,
                    "colour vs GT: GT points with no mesh vertex within this (metres) are left out")
        ->check(CLI::PositiveNumber);
    return [args] { return runEval(*args); };
}

}  // namespace vkmesh::cli
