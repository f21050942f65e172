// vkmesh: the command-line program. Every subcommand lives in its own file (host/commands.h lists them);
// this file registers them, parses the command line, runs the one given and turns errors into exit codes
// (2: bad input, named in the message; 3: an internal error).
#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "core/types.h"

int main(int argc, char** argv) {
    using namespace vkmesh::cli;
    CLI::App app{"vkmesh: real-time TSDF fusion and meshing on any Vulkan device"};
    app.require_subcommand(1);
    // In the order `vkmesh --help` lists them.
    const std::vector<std::pair<std::string, Run>> commands = {
        {"devices", addDevicesCommand(app)}, {"synth", addSynthCommand(app)},   {"frames", addFramesCommand(app)},
        {"fuse", addFuseCommand(app)},       {"export", addExportCommand(app)},  {"correct", addCorrectCommand(app)},
        {"merge", addMergeCommand(app)},
        {"deltas", addDeltasCommand(app)}, {"eval", addEvalCommand(app)},
        {"render", addRenderCommand(app)},   {"soak", addSoakCommand(app)},      {"view", addViewCommand(app)}};
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        for (const auto& [name, run] : commands)
            if (app.got_subcommand(name)) return run();
    } catch (const vkmesh::Error& e) {
        std::cerr << "vkmesh: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "vkmesh: internal error: " << e.what() << "\n";
        return 3;
    }
    return 0;
}
