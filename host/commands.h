// The subcommands of the `vkmesh` program, one file each (host/<name>_command.cpp); host/main.cpp only
// registers them and runs the one given.
//
// Each add*Command adds its subcommand and options to `app` and returns what main() runs after parsing when
// that subcommand was given: it returns the exit code and throws vkmesh::Error (naming the file or value at
// fault) on bad input. The options and the `--stats` JSON keys are an interface: users' scripts read them.
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace vkmesh::cli {

using Run = std::function<int()>;

Run addDevicesCommand(CLI::App& app);  // vkmesh devices: Vulkan devices and whether vkmesh can use them
Run addSynthCommand(CLI::App& app);    // vkmesh synth OUT_DIR: a synthetic sequence with ground truth (TUM layout)
Run addFramesCommand(CLI::App& app);   // vkmesh frames DATASET -o f.json: the frames fuse would use
Run addFuseCommand(CLI::App& app);     // vkmesh fuse DATASET -o mesh.ply: fuse on the GPU, write the mesh
Run addExportCommand(CLI::App& app);   // vkmesh export MAP -o mesh.ply: the mesh of a saved map (fuse --save)
Run addCorrectCommand(CLI::App& app);  // vkmesh correct MAP --trajectory T -o mesh.ply: re-fuse frames whose poses changed
Run addMergeCommand(CLI::App& app);    // vkmesh merge A.vkmap B.vkmap -o C.vkmap: the sum of saved maps, with its mesh
Run addDeltasCommand(CLI::App& app);   // vkmesh deltas STREAM -o mesh.ply: replay a mesh-delta stream
Run addEvalCommand(CLI::App& app);     // vkmesh eval MESH --gt GT.ply: accuracy, completeness, F-score
Run addRenderCommand(CLI::App& app);   // vkmesh render MESH -o view.png: offscreen picture of a mesh
Run addSoakCommand(CLI::App& app);     // vkmesh soak -o soak.csv: long synthetic run, occupancy per frame
Run addViewCommand(CLI::App& app);     // vkmesh view FILE: the browser viewer for a mesh, map or delta stream

}  // namespace vkmesh::cli
