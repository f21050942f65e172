// `vkmesh eval`: quality of a mesh (or point cloud) against ground-truth surface points.
//   vkmesh eval MESH.ply --gt GT.ply [--dataset DIR [--frame-stride K]] [--spacing 0.005]
//               [--thresholds 0.01,0.02,0.05] [--max-distance 0.2] [--json out.json]
// Prints accuracy, completeness and precision / recall / F-score per threshold; see src/eval/evaluate.h.
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace vkmesh {

// Adds the `eval` subcommand to `app` and returns what main() runs when app.got_subcommand("eval") after
// parsing: it returns the exit code (0) and throws vkmesh::Error (naming the file or value) on bad input.
std::function<int()> addEvalCommand(CLI::App& app);

}  // namespace vkmesh
