// `vkmesh render`: headless offscreen rendering of a mesh to a PNG with a Vulkan graphics pipeline.
//   vkmesh render MESH.ply -o view.png [--width 800 --height 600]
//                 [--camera eye_x,eye_y,eye_z,target_x,target_y,target_z] [--color shade|normal|age|rgb]
// The work is done by vkmesh::render::renderMeshFile (src/render/mesh_renderer.h), which the tests call too,
// and io::writePng (src/io/png.h).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "cli_options.h"
#include "commands.h"
#include "io/png.h"
#include "render/mesh_renderer.h"
#include "vk/context.h"

namespace vkmesh::cli {

namespace {
struct RenderArgs {
    std::string mesh;
    std::string output;
    int width = 800;
    int height = 600;
    std::string camera;
    std::string color = "auto";
    DeviceArgs device;
};
}  // namespace

Run addRenderCommand(CLI::App& app) {
    auto args = std::make_shared<RenderArgs>();
    auto* cmd = app.add_subcommand("render", "render a mesh offscreen to a PNG (Vulkan graphics pipeline)");
    cmd->add_option("MESH", args->mesh, "mesh file (.ply)")->required();
    cmd->add_option("-o,--output", args->output, "PNG file to write")->required();
    cmd->add_option("--width", args->width, "image width in pixels")->check(CLI::Range(1, 16384));
    cmd->add_option("--height", args->height, "image height in pixels")->check(CLI::Range(1, 16384));
    cmd->add_option("--camera", args->camera,
                    "eye_x,eye_y,eye_z,target_x,target_y,target_z (world z up, 60 degree vertical field of view; "
                    "default: a three-quarter view from outside the mesh's bounding box)");
    // Checked by parseColorMode so that a bad value is reported like every other vkmesh error.
    cmd->add_option("--color", args->color, "shade (Phong, headlight), normal (normal as RGB), age (red new .. blue old) or rgb (the fused vertex "
                    "colours); default: rgb when the mesh has colours, else shade");
    args->device.add(cmd);
    return [args]() {
        render::RenderOptions options;
        options.width = args->width;
        options.height = args->height;
        options.color = render::parseColorMode(args->color);
        if (!args->camera.empty()) options.camera = render::parseCamera(args->camera);
        vk::Context context(args->device.contextOptions());
        render::Image image = render::renderMeshFile(context, args->mesh, options);
        io::writePng(args->output, image);
        std::cout << "vkmesh render: " << args->mesh << " -> " << args->output << " (" << image.width << "x" << image.height
                  << ", " << args->color << ") on " << context.info().name << "\n";
        return 0;
    };
}

}  // namespace vkmesh::cli
