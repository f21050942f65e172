// An application that owns its Vulkan device and embeds vkmesh (api/reconstructor.h): every frame it
// hands vkmesh a depth image, then draws vkmesh's mesh straight from vkmesh's GPU buffers (no copy
// through the host) from the sensor's viewpoint and writes the picture to a file. Depth comes from the
// built-in synthetic room, so the example needs no data. It links vkmesh::vkmesh only (Vulkan, no image
// library), so the pictures are binary PPM, which takes a dozen lines to write; an application that wants
// PNGs links vkmesh::io and calls io::writePng (io/png.h), as the vkmesh CLI does.
//
//   vkmesh_embed_example --frames 24 --out out/embed      (VKMESH_VALIDATION=1: validation layer on, and
//                                                          any validation message makes it exit 1)
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "api/reconstructor.h"
#include "app_device.h"
#include "render/mesh_renderer.h"
#include "synth/synthetic_scene.h"

namespace {

// Binary PPM (P6): a header and the RGB bytes, top row first; the renderer's alpha is dropped.
void writePpm(const std::filesystem::path& path, const vkmesh::render::Image& image) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "P6\n" << image.width << " " << image.height << "\n255\n";
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) out.write(reinterpret_cast<const char*>(image.pixel(x, y)), 3);
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App cli("vkmesh embedding example: fuse a synthetic room, draw each frame from vkmesh's GPU buffers");
    int frames = 24, width = 320, height = 240;
    std::string outDir = "out/embed";
    cli.add_option("--frames", frames, "frames to fuse")->check(CLI::Range(1, 10000));
    cli.add_option("--width", width, "depth and picture width")->check(CLI::Range(16, 4096));
    cli.add_option("--height", height, "depth and picture height")->check(CLI::Range(16, 4096));
    cli.add_option("--out", outDir, "folder for frame_NNN.ppm");
    CLI11_PARSE(cli, argc, argv);
    const char* env = std::getenv("VKMESH_VALIDATION");
    const bool validation = env && *env && std::strcmp(env, "0") != 0;

    try {
        std::filesystem::create_directories(outDir);
        // 1. The application's own Vulkan objects.
        vkmesh::example::AppDevice app(validation);
        size_t messages = 0;
        {
            // 2. vkmesh on them, and the application's renderer on the same device and queue family.
            vkmesh::ReconstructorOptions options;
            options.volume.params.voxelSize = 0.04f;
            options.volume.params.maxDepth = 6.0f;
            options.volume.blockCapacity = 8192;
            options.trackDeltas = true;   // what a remote viewer would be sent, counted below
            vkmesh::Reconstructor reconstructor(app.external(), options);
            vkmesh::vk::Context renderContext(app.external());
            vkmesh::render::MeshRenderer renderer(renderContext);

            const auto scene = vkmesh::synth::SyntheticScene::defaultRoom();
            const vkmesh::Intrinsics intrinsics = vkmesh::synth::kinectIntrinsics(width, height);
            const auto poses = vkmesh::synth::cameraPath(size_t(frames));
            for (int i = 0; i < frames; ++i) {
                vkmesh::synth::RenderOptions noisy;
                noisy.noise = true;
                noisy.seed = uint32_t(i + 1);
                const vkmesh::Pose& pose = poses[size_t(i)];
                // 3. Fuse. When integrate() returns, the mesh buffers hold this frame's mesh.
                vkmesh::gpu::FrameReport report = reconstructor.integrate(scene.renderDepth(intrinsics, pose, noisy), intrinsics, pose);
                for (const auto& w : report.warnings) std::cerr << "warning: " << w << "\n";
                // 4. Draw from vkmesh's buffers (the renderer records Reconstructor::recordMeshReadBarrier
                //    before its indirect draw; see the contract in api/reconstructor.h).
                vkmesh::gpu::MeshBuffers mesh = reconstructor.meshBuffers();
                vkmesh::render::RenderOptions view;
                view.width = width;
                view.height = height;
                view.camera = vkmesh::render::sensorCamera(pose, intrinsics);
                Eigen::Vector3f eye = pose.block<3, 1>(0, 3).cast<float>();
                Eigen::Vector3f reach = Eigen::Vector3f::Constant(options.volume.params.maxDepth);
                char name[32];
                std::snprintf(name, sizeof(name), "frame_%03d.ppm", i);
                if (mesh.triangleCount > 0)
                    writePpm(std::filesystem::path(outDir) / name, renderer.render(mesh, eye - reach, eye + reach, view));
                const vkmesh::MeshDelta& delta = reconstructor.lastDelta();
                std::printf("frame %3d: %7u triangles, %7u vertices; delta +%zu ~%zu -%zu records\n", i + 1, mesh.triangleCount,
                            mesh.vertexCount, delta.count(vkmesh::DeltaKind::Added), delta.count(vkmesh::DeltaKind::Changed),
                            delta.count(vkmesh::DeltaKind::Removed));
            }
        }
        // 5. vkmesh is gone; the application's device lives on.
        messages = app.takeMessages().size();
        std::printf("wrote %d pictures to %s; validation %s, %zu messages\n", frames, outDir.c_str(), validation ? "on" : "off", messages);
        return messages == 0 ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 2;
    }
}
