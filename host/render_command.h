// `vkmesh render`: headless offscreen rendering of a mesh to a PNG with a Vulkan graphics pipeline.
//   vkmesh render MESH.ply -o view.png [--width 800 --height 600]
//                 [--camera eye_x,eye_y,eye_z,target_x,target_y,target_z] [--color shade|normal|age]
// The work is done by vkmesh::render::renderMeshFile (src/render/mesh_renderer.h), which the tests call too,
// and io::writePng (src/io/png.h).
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace vkmesh {

// Adds the `render` subcommand to `app` and returns what main() runs when app.got_subcommand("render")
// after parsing: it returns the exit code (0) and throws vkmesh::Error (naming the file or value) on bad input.
std::function<int()> addRenderCommand(CLI::App& app);

}  // namespace vkmesh
