// `vkmesh soak`: a long run over the synthetic room with revisits, recording per frame how full the hash,
// the block pool and the mesh heaps are, to show that bounded maps (--keep-radius, --recycle) keep them flat.
//   vkmesh soak -o soak.csv [--frames 3000 --laps 6 --width 160 --height 120 --voxel 0.05]
//               [--keep-radius 2.0] [--recycle] [--summary summary.json]
// bench/soak_plot.py draws the CSVs of several runs.
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace vkmesh {

// Adds the `soak` subcommand to `app`; the returned function runs it (exit code 0, throws vkmesh::Error).
std::function<int()> addSoakCommand(CLI::App& app);

}  // namespace vkmesh
