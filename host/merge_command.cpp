// `vkmesh merge A.vkmap B.vkmap ... -o C.vkmap [--mesh C.ply]`: the sum of saved maps (docs/SCALING.md). Maps
// fused from parts of one recording (or from several recordings of one place, in one world frame) add up to the
// map of all their frames: TSDF sums and counts added corner by corner, blocks united, colour combined by its
// weights; the mesh is built from the sum (the mesh one run fusing every frame would have), and the frame stores
// saved beside the inputs are carried over so that the merged map can be corrected. Maps that do not add up
// (other settings, bounded maps, a corner past its count) are refused naming what differs; nothing is written then.
//
// Unlike fuse and correct, where -o is the mesh, -o here is the map: the merged map is what this command makes.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/map_merge.h"
#include "api/run_stats_json.h"
#include "cli_options.h"
#include "core/icp_solve.h"
#include "commands.h"
#include "io/mesh_file.h"
#include "slam/session_join.h"
#include "slam/session_join_json.h"

namespace vkmesh::cli {

namespace {

struct MergeArgs {
    std::vector<std::string> maps;
    std::string output;
    std::string meshPath;
    std::string statsPath;
    double tileSize = 0;
    std::string tilesDir;
    bool noFrames = false;
    bool registerSessions = false;
    double framesBudgetMb = 1024;
    std::string framesSpill;
    DeviceArgs device;
};

int runMerge(const MergeArgs& args) {
    const std::filesystem::path out(args.output);
    if (out.extension() == ".ply" || out.extension() == ".obj" || out.extension() == ".glb")
        throw Error("-o " + args.output + ": -o is the merged map (.vkmap); write its mesh with --mesh " + args.output);
    if (args.output.empty() && args.tilesDir.empty()) throw Error("merge: give the merged map (-o C.vkmap), tiles (--tiles DIR --tile-size S), or both");
    if (args.output.empty() && !args.meshPath.empty()) throw Error("--mesh needs -o: without a merged map there is only --tiles");
    if (!args.tilesDir.empty() != (args.tileSize > 0)) throw Error("--tiles DIR and --tile-size S go together");
    if (!args.meshPath.empty()) meshFormatOf(args.meshPath);   // a mesh name vkmesh cannot write fails now, not after the merge
    MergeOptions options;
    options.device = args.device.contextOptions();
    options.keepFrames = !args.noFrames;
    options.frames.memoryBudgetBytes = size_t(args.framesBudgetMb * 1024 * 1024);
    options.frames.spillFolder = args.framesSpill;
    options.returnMesh = !args.meshPath.empty();
    options.tileSize = args.tileSize;
    if (!args.tilesDir.empty()) {
        std::filesystem::create_directories(args.tilesDir);
        options.tileSink = [&](const TileKey& t, const Mesh& mesh) {
            writeMesh(std::filesystem::path(args.tilesDir) / tileFileName(t), mesh);
        };
    }
    std::vector<std::filesystem::path> inputs(args.maps.begin(), args.maps.end());
    std::optional<slam::JoinReport> joined;
    if (args.registerSessions) {
        if (inputs.size() < 2) throw Error("--register joins two maps or more: the later ones are registered to the first");
        if (args.output.empty()) throw Error("--register needs -o: the joined map");
        slam::JoinOptions join;
        join.merge = options;
        joined = slam::joinSessions(inputs, out, join);
        for (size_t i = 0; i < joined->registrations.size(); ++i) {
            const slam::SessionRegistration& r = joined->registrations[i];
            const Pose& t = r.secondToFirst;
            std::cout << "vkmesh merge: " << inputs[i + 1].string() << " registered to " << inputs[0].string() << ": " << r.agreeing << " of "
                      << r.verified << " verified keyframe pairs agree (" << r.registrations << " tried), within " << r.spreadMetres * 100
                      << " cm and " << r.spreadDegrees << " degrees; moved " << translationMetres(t) << " m, turned " << rotationDegrees(t)
                      << " degrees\n";
        }
    }
    const MergeReport report = joined ? joined->merge : mergeMaps(inputs, out, options);
    for (const std::string& w : report.warnings) std::cerr << "warning: " << w << "\n";
    if (!args.meshPath.empty()) writeMesh(args.meshPath, report.mesh);
    std::cout << "vkmesh merge: " << inputs.size() << " maps, " << report.framesIntegrated << " frames, " << report.blocks << " blocks ("
              << report.sharedBlocks << " in more than one map)";
    if (!args.output.empty()) {
        std::cout << " -> " << out.string();
        if (!report.frameStorePath.empty())
            std::cout << " with " << report.framesStored << " frames kept" << (report.framesRenumbered ? " (renumbered)" : "");
        std::cout << "; mesh " << report.meshVertices << " vertices, " << report.meshTriangles << " triangles"
                  << (args.meshPath.empty() ? "" : " -> " + args.meshPath);
    }
    if (!args.tilesDir.empty())
        std::cout << "; " << report.tiles << " tiles of " << args.tileSize << " m, " << report.tileTriangles << " triangles -> " << args.tilesDir
                  << " (at most " << report.tileBlocksMax << " blocks on the GPU at once)";
    std::cout << "\n";
    if (!args.statsPath.empty()) {
        nlohmann::json stats = mergeReportJson(report);
        stats["output"] = out.string();
        if (!args.tilesDir.empty()) stats["tiles"]["path"] = args.tilesDir, stats["tiles"]["size_m"] = args.tileSize;
        if (!args.meshPath.empty()) stats["mesh"]["path"] = args.meshPath;
        if (joined) stats["registration"] = slam::joinReportJson(*joined, inputs);
        std::ofstream(args.statsPath) << stats.dump(2) << "\n";
    }
    return 0;
}

}  // namespace

Run addMergeCommand(CLI::App& app) {
    auto args = std::make_shared<MergeArgs>();
    auto* cmd = app.add_subcommand("merge", "add saved maps into one: the map of all their frames, with its mesh (docs/SCALING.md)");
    cmd->add_option("MAPS", args->maps, "maps (.vkmap) saved by vkmesh fuse --save with the same settings, their frame stores beside them")
        ->required();
    cmd->add_option("-o,--output", args->output, "the merged map (.vkmap; its frame store is written beside it)");
    cmd->add_option("--mesh", args->meshPath, "also write the merged map's mesh (.ply binary, .obj or .glb binary glTF)");
    cmd->add_option("--tiles", args->tilesDir,
                    "also write the mesh tile by tile into this folder (tile_X_Y_Z.ply), each tile meshed alone on the GPU; "
                    "without -o, only the tiles (the whole map is never on the GPU)");
    cmd->add_option("--tile-size", args->tileSize, "--tiles: the tiles' side in metres (whole blocks)")->check(CLI::PositiveNumber);
    cmd->add_option("--stats", args->statsPath, "write statistics as JSON (inputs, blocks, frames kept, mesh, tiles, ms)");
    cmd->add_flag("--register", args->registerSessions,
                  "the maps are sessions of one place, each in its own world frame: register each later map to the first by the frames "
                  "their stores keep, re-fuse its frames there, then add them (docs/SCALING.md, \"Sessions of one place\")");
    cmd->add_flag("--no-frames", args->noFrames, "do not carry the inputs' frame stores over (the merged map cannot be corrected then)");
    addSetting(cmd, "--frames-budget", args->framesBudgetMb);
    addSetting(cmd, "--frames-spill", args->framesSpill);
    args->device.add(cmd);
    return [args] { return runMerge(*args); };
}

}  // namespace vkmesh::cli
