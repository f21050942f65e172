#include "cli_options.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "io/mesh_file.h"

namespace vkmesh::cli {

namespace {

// The description of the first long name in CLI11's `names` ("--refine,!--no-refine" -> "--refine").
const SettingDescription& settingOf(const std::string& names) {
    size_t start = 0;
    while (start <= names.size()) {
        size_t end = names.find(',', start);
        if (end == std::string::npos) end = names.size();
        std::string name = names.substr(start, end - start);
        if (!name.empty() && name[0] == '!') name.erase(0, 1);
        if (name.rfind("--", 0) == 0) return setting(name);
        start = end + 1;
    }
    throw Error("option '" + names + "' has no long name to find its description by");
}

// The description's range or choices, and its deprecation message, on the option.
CLI::Option* described(CLI::Option* option, const SettingDescription& d) {
    if (!d.choices.empty()) {
        option->check(CLI::IsMember(d.choices));
    } else if (d.minExclusive && d.min == 0 && std::isinf(d.max)) {
        option->check(CLI::PositiveNumber);
    } else if (d.min == 0 && !d.minExclusive && std::isinf(d.max)) {
        option->check(CLI::NonNegativeNumber);
    } else if (!std::isinf(d.min) || !std::isinf(d.max)) {
        option->check(CLI::Range(d.min, d.max));
    }
    if (!d.deprecated.empty()) {
        const std::string message = "vkmesh: " + d.cli + " is deprecated and has no effect: " + d.deprecated + "\n";
        option->each([message](const std::string&) { std::cerr << message; });
    }
    return option;
}

template <class T>
CLI::Option* addDescribed(CLI::App* cmd, const std::string& names, T& value) {
    const SettingDescription& d = settingOf(names);
    return described(cmd->add_option(names, value, d.help), d);
}

}  // namespace

CLI::Option* addSetting(CLI::App* cmd, const std::string& names, float& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, double& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, int& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, uint32_t& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, size_t& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, std::string& value) { return addDescribed(cmd, names, value); }
CLI::Option* addSettingFlag(CLI::App* cmd, const std::string& names, bool& value) {
    const SettingDescription& d = settingOf(names);
    return described(cmd->add_flag(names, value, d.help), d);
}

void DatasetArgs::add(CLI::App* cmd) {
    cmd->add_option("DATASET", dataset,
                    "dataset folder (TUM, ICL-NUIM, Redwood, 7-Scenes, a folder with camera.json) or recording (ROS 1 .bag, "
                    "RealSense .bag, .mcap, rosbag2 .db3 or folder)")
        ->required();
    addSetting(cmd, "--frames", frames);
    addSetting(cmd, "--max-depth", maxDepth);
    addSetting(cmd, "--intrinsics", intrinsics);
    addSetting(cmd, "--depth-scale", depthScale);
    addSetting(cmd, "--depth-topic", depthTopic);
    addSetting(cmd, "--color-topic", colorTopic);
    addSetting(cmd, "--info-topic", infoTopic);
}

std::unique_ptr<Dataset> DatasetArgs::open() const {
    DatasetOptions options;
    if (!intrinsics.empty()) options.intrinsics = parseIntrinsics(intrinsics);
    if (depthScale > 0) options.depthScale = depthScale;
    options.maxDepth = maxDepth;
    options.maxFrames = frames;
    options.requirePoses = !posesOptional;
    options.depthTopic = depthTopic;
    options.colorTopic = colorTopic;
    options.infoTopic = infoTopic;
    return Dataset::open(dataset, options);
}

void VolumeOptions::addCommon(CLI::App* cmd) {
    addSetting(cmd, "--voxel", voxel);
    addSetting(cmd, "--blocks", blocks);
    addSettingFlag(cmd, "--no-grow", noGrow);
    addSetting(cmd, "--resident-blocks", residentBlocks);
    addSetting(cmd, "--keep-radius", keepRadius);
    addSettingFlag(cmd, "--recycle", recycle);
    addSetting(cmd, "--recycle-after", recycleAfter);
    addSetting(cmd, "--starve-weight", starveWeight);
}

void VolumeOptions::addTuning(CLI::App* cmd) {
    addSetting(cmd, "--mode", mode);
    addSettingFlag(cmd, "--refine,!--no-refine", refine);
    addSetting(cmd, "--refine-eps", refineEps);
    addSettingFlag(cmd, "--lock-free", lockFree);
    addSetting(cmd, "--vertices", vertices);
    addSetting(cmd, "--chunks", chunks);
    addSetting(cmd, "--hash-slots", hashSlots);
    addSetting(cmd, "--trunc", truncVoxels);
    // Deprecated (map version 2): fusion keeps exact integer sums, which a cap would make impossible to undo.
    addSetting(cmd, "--max-weight", maxWeight);
    addSetting(cmd, "--min-weight", minWeight);
    addSetting(cmd, "--alloc-stride", allocStride);
    addSettingFlag(cmd, "--alloc-tiles", allocTiles);
    addSettingFlag(cmd, "--alloc-pixels", allocPixels)->excludes("--alloc-tiles");
    addSettingFlag(cmd, "--no-color", noColor);
    addSetting(cmd, "--color-mode", colorMode);
    addSetting(cmd, "--color-recency", colorRecency);
}

gpu::GpuVolumeConfig VolumeOptions::toConfig(float maxDepth, int width, int height, bool inputHasColor) const {
    gpu::GpuVolumeConfig config;
    config.params.voxelSize = voxel;
    config.params.truncVoxels = truncVoxels;
    config.params.maxWeight = maxWeight;
    config.params.maxDepth = maxDepth;
    config.params.allocationStride = allocStride;
    config.params.allocationTiles = allocTiles && !allocPixels;
    config.minMeshWeight = minWeight;
    config.meshMode = incremental() ? gpu::MeshMode::Incremental : gpu::MeshMode::Baseline;
    config.refine = refine;
    config.refineEpsilonVoxels = refineEps;
    config.lockFree = lockFree;
    config.blockCapacity = blocks;
    config.vertexCapacity = vertices;
    config.chunkCapacity = chunks;
    config.hashCapacity = hashSlots;
    config.residentBlocks = residentBlocks;
    config.keepRadius = keepRadius;
    config.recycle = recycle;
    config.recycleAfterFrames = recycleAfter;
    config.starveWeight = starveWeight;
    config.growCapacities = !noGrow;
    config.imageWidth = width;
    config.imageHeight = height;
    config.params.colorFusion = !inputHasColor || noColor ? ColorFusion::Off
                                : colorMode == "recent"   ? ColorFusion::Recent
                                                          : ColorFusion::Average;
    config.params.colorRecency = colorRecency;
    return config;
}

void DeviceArgs::add(CLI::App* cmd) {
    addSetting(cmd, "--device", device);
    addSettingFlag(cmd, "--validation", validation);
}

void MeshOutputArgs::add(CLI::App* cmd) {
    addSetting(cmd, "-o,--output", path)->required();
    addSetting(cmd, "--simplify", simplify);
}

void MeshOutputArgs::check() const {
    meshFormatOf(path);
    checkSimplifyRatio(simplify, "--simplify");
}

std::optional<SimplifyReport> MeshOutputArgs::write(const Mesh& mesh) const {
    if (!simplifying()) {
        writeMesh(path, mesh);
        return std::nullopt;
    }
    SimplifyReport report;
    writeMesh(path, simplifyMesh(mesh, simplify, &report));
    return report;
}

std::string describe(const SimplifyReport& r) {
    char line[200];
    std::snprintf(line, sizeof line, "simplified to %zu of %zu triangles (--simplify %g), geometric error %.2f mm", r.trianglesAfter,
                  r.trianglesBefore, r.ratio, 1000 * r.errorMetres);
    return line;
}

}  // namespace vkmesh::cli
