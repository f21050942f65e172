// `vkmesh export MAP -o mesh.ply|.obj|.glb [--simplify RATIO]`: the mesh of a saved map (docs/MAPFILE.md), without
// fusing anything: the map is loaded on the GPU and its mesh compacted and written, as `vkmesh fuse -o` would have
// after its last frame (simplified, a copy, with --simplify: docs/MESH_FILES.md).
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "api/exported_mesh.h"
#include "cli_options.h"
#include "commands.h"
#include "core/map_format.h"
#include "gpu/gpu_volume.h"
#include "vk/context.h"

namespace vkmesh::cli {

namespace {

struct ExportArgs {
    std::string map;
    MeshOutputArgs output;   // -o, --simplify
    DeviceArgs device;
};

int runExport(const ExportArgs& args) {
    args.output.check();
    const map::MapData m = map::readFile(args.map);   // checked before a device is opened
    vk::Context context(args.device.contextOptions());
    const gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(m);
    std::unique_ptr<gpu::GpuVolume> volume = gpu::GpuVolume::load(context, m, config, args.map);
    Mesh mesh;
    if (config.meshMode == gpu::MeshMode::Incremental) {
        mesh = toMesh(volume->exportMesh(), volume->frameNumber());   // ages in the GPU's frame numbers, as fuse writes them
    } else {
        gpu::TriangleSoup soup = volume->extractBaselineMesh();
        mesh.positions = soup.vertices;
        for (uint32_t t = 0; t < soup.triangleCount(); ++t) mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    const std::filesystem::path out(args.output.path);
    const std::optional<SimplifyReport> simplified = args.output.write(mesh);   // a copy; the map is not changed
    std::cout << "vkmesh export: " << args.map << " (" << m.blocks.size() << " blocks, " << m.framesIntegrated << " frames, voxel "
              << m.settings.voxelSize << " m): " << mesh.positions.size() << " vertices, " << mesh.triangles.size() << " triangles -> "
              << out.string() << "\n";
    if (simplified) std::cout << "  " << describe(*simplified) << "\n";
    return 0;
}

}  // namespace

Run addExportCommand(CLI::App& app) {
    auto args = std::make_shared<ExportArgs>();
    auto* cmd = app.add_subcommand("export", "write the mesh of a saved map (vkmesh fuse --save) without fusing");
    cmd->add_option("MAP", args->map, "map file (.vkmap)")->required();
    args->output.add(cmd);
    args->device.add(cmd);
    return [args] { return runExport(*args); };
}

}  // namespace vkmesh::cli
