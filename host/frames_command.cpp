// `vkmesh frames DATASET -o frames.json`: the frames `fuse` would use (absolute depth paths, timestamps,
// camera-to-world poses) and the calibration, as JSON, so that peer programs fuse exactly the same input.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_options.h"
#include "commands.h"

namespace vkmesh::cli {

namespace {

struct FramesArgs {
    DatasetArgs data;
    std::string out;
};

int runFrames(const FramesArgs& args) {
    using json = nlohmann::json;
    auto dataset = args.data.open();
    const Intrinsics& k = dataset->intrinsics();
    json j;
    j["dataset"] = std::filesystem::absolute(dataset->folder()).string();
    j["kind"] = toString(dataset->kind());
    j["depth_scale"] = dataset->depthScale();
    j["max_depth"] = args.data.maxDepth;
    j["intrinsics"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"width", k.width}, {"height", k.height}};
    j["has_color"] = dataset->hasColor();
    if (!dataset->description().empty()) j["recording"] = dataset->description();
    j["frames"] = json::array();
    for (size_t i = 0; i < dataset->size(); ++i) {
        const FrameInfo& f = dataset->frame(i);
        std::vector<double> m(16);
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m[r * 4 + c] = f.cameraToWorld(r, c);
        // color_path: the frame's colour image as Dataset::loadColor reads it, null when it has none (the
        // file is not registered here: with camera.json colour intrinsics a peer must resample it itself).
        json frame = {{"index", f.index}, {"timestamp", f.timestamp},
                      {"depth_path", std::filesystem::absolute(f.depthPath).string()}, {"camera_to_world", m},
                      {"color_path", f.colorPath.empty() ? json(nullptr) : json(std::filesystem::absolute(f.colorPath).string())}};
        // A recording's frames are messages in one file: which ones.
        if (!f.depthRecord.empty()) frame["depth_record"] = f.depthRecord;
        if (!f.colorRecord.empty()) frame["color_record"] = f.colorRecord;
        j["frames"].push_back(std::move(frame));
    }
    std::ofstream file(args.out);
    if (!file) throw Error("cannot write " + args.out);
    file << j.dump(1) << "\n";
    std::cerr << "wrote " << dataset->size() << " frames to " << args.out << "\n";
    return 0;
}

}  // namespace

Run addFramesCommand(CLI::App& app) {
    auto args = std::make_shared<FramesArgs>();
    auto* cmd = app.add_subcommand("frames", "write the frames fuse would use (paths, poses, intrinsics) as JSON");
    args->data.add(cmd);
    cmd->add_option("-o,--output", args->out, "JSON file to write")->required();
    return [args] { return runFrames(*args); };
}

}  // namespace vkmesh::cli
