// `vkmesh deltas STREAM -o mesh.ply`: what a remote viewer does with a `fuse --deltas` stream (docs/DELTAS.md):
// apply every frame's changes and write the mesh it ends with.
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "core/mesh_delta.h"
#include "io/delta_stream.h"
#include "io/mesh_file.h"

namespace vkmesh::cli {

namespace {

struct DeltasArgs {
    std::string stream, output;
    uint32_t untilFrame = 0;
};

int runDeltas(const DeltasArgs& a) {
    if (!a.output.empty()) meshFormatOf(a.output);   // before the stream is read
    MeshReplica replica;
    size_t frames = 0, records = 0;
    readDeltaStream(a.stream, [&](const MeshDelta& d) {
        if (a.untilFrame && d.frame > a.untilFrame) return;
        replica.apply(d);
        ++frames;
        records += d.vertices.size() + d.triangles.size();
    });
    Mesh mesh = replica.toMesh();
    if (!a.output.empty()) writeMesh(a.output, mesh);
    std::cout << "vkmesh deltas: " << frames << " frames, " << records << " records from " << a.stream << " -> mesh at frame "
              << replica.lastFrame() << ": " << mesh.positions.size() << " vertices, " << mesh.triangles.size() << " triangles"
              << (a.output.empty() ? "" : " -> " + a.output) << "\n";
    return 0;
}

}  // namespace

Run addDeltasCommand(CLI::App& app) {
    auto args = std::make_shared<DeltasArgs>();
    auto* cmd = app.add_subcommand("deltas", "replay a mesh-delta stream as a remote viewer would and write the mesh it ends with");
    cmd->add_option("STREAM", args->stream, "stream written by fuse --deltas")->required();
    cmd->add_option("-o,--output", args->output, "mesh file to write (.ply binary, .obj or .glb binary glTF)");
    cmd->add_option("--until-frame", args->untilFrame, "stop after this frame number (0 = all)");
    return [args] { return runDeltas(*args); };
}

}  // namespace vkmesh::cli
