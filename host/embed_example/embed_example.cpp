// An application that owns its Vulkan device and embeds vkmesh (api/reconstructor.h): every frame it
// hands vkmesh a depth image, then draws vkmesh's mesh straight from vkmesh's GPU buffers (no copy
// through the host) from the sensor's viewpoint and writes the picture to a file. Depth comes from the
// built-in synthetic room, so the example needs no data. It links vkmesh::vkmesh only (Vulkan, no image
// library), so the pictures are binary PPM, which takes a dozen lines to write; an application that wants
// PNGs links vkmesh::io and calls io::writePng (io/png.h), as the vkmesh CLI does.
//
//   vkmesh_embed_example --frames 24 --out out/embed      (VKMESH_VALIDATION=1: validation layer on, and
//                                                          any validation message makes it exit 1)
//   vkmesh_embed_example --async ...                      the asynchronous form: integrateAsync() returns at
//                                                          once; the draw waits on vkmesh's timeline semaphore
//                                                          on the GPU
//   vkmesh_embed_example --compare --pictures-every 0     the application's loop time per frame (make the next
//                                                          depth image + integrate), blocking against
//                                                          asynchronous, alternating runs on the same frames
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <vector>

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

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
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
    bool async = false, compare = false;
    int picturesEvery = 1, repeats = 2;
    cli.add_flag("--async", async, "integrateAsync: fuse frame N+1 while frame N is drawn");
    cli.add_flag("--compare", compare, "time the application's loop, blocking against asynchronous (alternating runs)");
    cli.add_option("--pictures-every", picturesEvery, "draw and write every Kth frame (0: none)")->check(CLI::Range(0, 10000));
    cli.add_option("--repeats", repeats, "--compare: runs of each form")->check(CLI::Range(1, 100));
    CLI11_PARSE(cli, argc, argv);
    const char* env = std::getenv("VKMESH_VALIDATION");
    const bool validation = env && *env && std::strcmp(env, "0") != 0;

    try {
        std::filesystem::create_directories(outDir);
        // 1. The application's own Vulkan objects.
        vkmesh::example::AppDevice app(validation);
        size_t messages = 0, pictures = 0;
        {
            // 2. vkmesh on them, and the application's renderer on the same device and queue family.
            vkmesh::ReconstructorOptions options;
            options.volume.params.voxelSize = 0.04f;
            options.volume.params.maxDepth = 6.0f;
            options.volume.blockCapacity = 8192;
            options.trackDeltas = true;   // what a remote viewer would be sent, counted below
            vkmesh::vk::Context renderContext(app.external());
            vkmesh::render::MeshRenderer renderer(renderContext);
            const auto scene = vkmesh::synth::SyntheticScene::defaultRoom();
            const vkmesh::Intrinsics intrinsics = vkmesh::synth::kinectIntrinsics(width, height);
            const auto poses = vkmesh::synth::cameraPath(size_t(frames));

            // One run: returns the application's loop time per frame (ms): making the depth image (standing
            // in for the application's own work: a simulator, a sensor driver) plus the integrate call.
            auto run = [&](bool asyncForm, bool print) {
                vkmesh::Reconstructor reconstructor(app.external(), options);
                std::vector<double> loopMs;
                for (int i = 0; i < frames; ++i) {
                    const auto start = std::chrono::steady_clock::now();
                    vkmesh::synth::RenderOptions noisy;
                    noisy.noise = true;
                    noisy.seed = uint32_t(i + 1);
                    const vkmesh::Pose& pose = poses[size_t(i)];
                    const vkmesh::DepthImage depth = scene.renderDepth(intrinsics, pose, noisy);
                    // 3. Fuse. Blocking: when integrate() returns, the mesh buffers hold this frame's mesh.
                    //    Asynchronous: integrateAsync() returns at once with the buffers this frame writes and
                    //    the timeline value at which they hold its mesh; the last frame's report comes with it.
                    vkmesh::gpu::MeshBuffers mesh;
                    vkmesh::vk::SubmitSync drawAfterFusion;
                    std::vector<std::string> warnings;
                    if (asyncForm) {
                        vkmesh::Reconstructor::AsyncFrame a = reconstructor.integrateAsync(depth, nullptr, intrinsics, pose);
                        mesh = a.mesh;
                        drawAfterFusion.wait = {a.ready};
                        drawAfterFusion.waitStages = {VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT};
                        drawAfterFusion.waitValues = {a.readyValue};
                        if (a.previous) warnings = a.previous->warnings;
                    } else {
                        warnings = reconstructor.integrate(depth, intrinsics, pose).warnings;
                        mesh = reconstructor.meshBuffers();
                    }
                    loopMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
                    for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
                    // 4. Draw from vkmesh's buffers (the renderer records Reconstructor::recordMeshReadBarrier
                    //    before its indirect draw, and waits on the GPU for the asynchronous frame's value; see
                    //    the contract in api/reconstructor.h).
                    if (picturesEvery > 0 && i % picturesEvery == 0) {
                        vkmesh::render::RenderOptions view;
                        view.width = width;
                        view.height = height;
                        view.camera = vkmesh::render::sensorCamera(pose, intrinsics);
                        Eigen::Vector3f eye = pose.block<3, 1>(0, 3).cast<float>();
                        Eigen::Vector3f reach = Eigen::Vector3f::Constant(options.volume.params.maxDepth);
                        char name[32];
                        std::snprintf(name, sizeof(name), "frame_%03d.ppm", i);
                        writePpm(std::filesystem::path(outDir) / name, renderer.render(mesh, eye - reach, eye + reach, view, drawAfterFusion));
                        ++pictures;
                    }
                    if (print) {
                        const vkmesh::MeshDelta& delta = reconstructor.lastDelta();
                        if (asyncForm)
                            std::printf("frame %3d submitted; frame %3d's delta +%zu ~%zu -%zu records\n", i + 1, i,
                                        delta.count(vkmesh::DeltaKind::Added), delta.count(vkmesh::DeltaKind::Changed),
                                        delta.count(vkmesh::DeltaKind::Removed));
                        else
                            std::printf("frame %3d: %7u triangles, %7u vertices; delta +%zu ~%zu -%zu records\n", i + 1, mesh.triangleCount,
                                        mesh.vertexCount, delta.count(vkmesh::DeltaKind::Added), delta.count(vkmesh::DeltaKind::Changed),
                                        delta.count(vkmesh::DeltaKind::Removed));
                    }
                }
                if (auto last = reconstructor.finish()) {
                    for (const auto& w : last->warnings) std::cerr << "warning: " << w << "\n";
                    if (print) std::printf("frame %3d finished: %u live triangles\n", frames, last->counters.liveTriangles);
                }
                return loopMs;
            };

            if (!compare) {
                run(async, true);
            } else {
                // Alternating runs on the same frames; the first frame of each (pipeline warm-up, first
                // allocation) is left out of the median.
                std::vector<double> blockingMs, asyncMs;
                for (int r = 0; r < repeats; ++r) {
                    for (bool asyncForm : {false, true}) {
                        std::vector<double> ms = run(asyncForm, false);
                        if (ms.size() > 1) ms.erase(ms.begin());
                        (asyncForm ? asyncMs : blockingMs).insert((asyncForm ? asyncMs : blockingMs).end(), ms.begin(), ms.end());
                    }
                }
                std::printf("application loop per frame (make depth + integrate), median over %zu frames: blocking %.2f ms, "
                            "asynchronous %.2f ms (x%.2f)\n",
                            blockingMs.size(), median(blockingMs), median(asyncMs), median(asyncMs) / std::max(1e-9, median(blockingMs)));
            }
        }
        // 5. vkmesh is gone; the application's device lives on.
        messages = app.takeMessages().size();
        std::printf("wrote %zu pictures to %s; validation %s, %zu messages\n", pictures, outDir.c_str(), validation ? "on" : "off", messages);
        return messages == 0 ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 2;
    }
}
