// `vkmesh view FILE`: serves the browser viewer (docs/VIEWER.md) for a mesh (.ply or .glb), a saved map (.vkmap, its mesh
// exported on the GPU) or a mesh-delta stream (.deltas, played frame by frame with a slider) until Ctrl-C.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "core/types.h"

#ifdef VKMESH_HAVE_VIEWER
#include "api/exported_mesh.h"
#include "cli_options.h"
#include "core/map_format.h"
#include "gpu/gpu_volume.h"
#include "io/delta_stream.h"
#include "io/mesh_file.h"
#include "viewer/viewer_server.h"
#include "vk/context.h"
#endif

namespace vkmesh::cli {

namespace {

struct ViewArgs {
    std::string file;
    std::string host = "127.0.0.1";
    uint16_t port = 8080;
    double fps = 30;
    double seconds = -1;
    bool quiet = false;
#ifdef VKMESH_HAVE_VIEWER
    DeviceArgs device;
#endif
};

#ifdef VKMESH_HAVE_VIEWER
int runView(const ViewArgs& a) {
    const std::filesystem::path path(a.file);
    const std::string ext = path.extension().string();
    if (ext != ".ply" && ext != ".glb" && ext != ".vkmap" && ext != ".deltas")
        throw Error(a.file + ": cannot view this kind of file (a .ply or .glb mesh, a .vkmap map or a .deltas stream)");
    // Read (and check) the file before the port is taken.
    Mesh mesh;
    std::vector<MeshDelta> frames;
    std::string what;
    if (ext == ".ply" || ext == ".glb") {
        mesh = readMesh(path);
        what = std::to_string(mesh.triangles.size()) + " triangles";
    } else if (ext == ".vkmap") {
        const map::MapData m = map::readFile(path);
        vk::Context context(a.device.contextOptions());
        const gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(m);
        if (config.meshMode != gpu::MeshMode::Incremental) throw Error(a.file + ": a baseline-mode map keeps no mesh to view");
        auto volume = gpu::GpuVolume::load(context, m, config, path);
        mesh = toMesh(volume->exportMesh(), volume->frameNumber());
        what = std::to_string(mesh.triangles.size()) + " triangles of a map of " + std::to_string(m.framesIntegrated) + " frames";
    } else {
        size_t records = 0;
        readDeltaStream(path, [&](const MeshDelta& d) {
            frames.push_back(d);
            records += d.vertices.size() + d.triangles.size();
        });
        what = std::to_string(frames.size()) + " frames, " + std::to_string(records) + " records";
    }
    // Ctrl-C is taken by this thread (sigwait) and never by the server's: blocked before that thread starts.
    viewer::blockStopSignals();
    viewer::ServerOptions options;
    options.host = a.host;
    options.port = a.port;
    options.playFps = a.fps;
    options.quiet = a.quiet;
    viewer::Server server(options);
    if (ext == ".deltas")
        server.setStream(std::move(frames));
    else
        server.setMesh(mesh);
    server.onReport([](const std::vector<std::pair<std::string, double>>& report) {
        std::cout << "vkmesh view: page report:";
        for (const auto& [k, v] : report) std::cout << " " << k << "=" << v;
        std::cout << std::endl;
    });
    std::cout << "vkmesh view: " << a.file << " (" << what << ") at " << server.url()
              << (a.seconds < 0 ? " (Ctrl-C stops)" : "") << std::endl;
    const bool signalled = viewer::waitForStopSignal(a.seconds);
    server.stop();
    const viewer::ServerStats s = server.stats();
    std::cout << "vkmesh view: " << (signalled ? "stopped" : "done") << ": " << s.pagesConnected << " pages, " << s.messagesSent
              << " messages, " << s.bytesSent << " bytes sent" << std::endl;
    return 0;
}
#else
int runView(const ViewArgs&) {
    throw Error("this vkmesh was built without the browser viewer: it needs libboost-dev and libjs-three at build time "
                "(scripts/install_deps.sh installs them)");
}
#endif

}  // namespace

Run addViewCommand(CLI::App& app) {
    auto args = std::make_shared<ViewArgs>();
    auto* cmd = app.add_subcommand("view", "serve the browser viewer for a mesh, a map or a delta stream (docs/VIEWER.md)");
    cmd->add_option("FILE", args->file, ".ply or .glb mesh, .vkmap map or .deltas stream (fuse --deltas)")->required();
    cmd->add_option("--port", args->port, "TCP port (default 8080)");
    cmd->add_option("--host", args->host, "address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: every interface)");
    cmd->add_option("--fps", args->fps, "a stream's playback speed in frames per second (default 30)")->check(CLI::PositiveNumber);
    cmd->add_option("--seconds", args->seconds, "stop after this many seconds (default: at Ctrl-C)");
    cmd->add_flag("-q,--quiet", args->quiet, "no line per page connected or disconnected");
#ifdef VKMESH_HAVE_VIEWER
    args->device.add(cmd);
#endif
    return [args] { return runView(*args); };
}

}  // namespace vkmesh::cli
