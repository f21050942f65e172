// Size and write time of one mesh as binary PLY, OBJ and binary glTF, the time to read the .glb back, and the time
// and error of --simplify at a few ratios (docs/MESH_FILES.md; docs/RESULTS.md). One thread, the best of --repeat
// runs; files go to --out (default /tmp). The mesh is any PLY, e.g. what `vkmesh fuse -o mesh.ply` wrote.
//
// Not part of the CMake build (a measurement, linked against the build's libraries). Build and run from the checkout
// after building vkmesh_io:
//   g++ -std=c++20 -O2 -Isrc -isystem /usr/include/eigen3 bench/mesh_file_bench.cpp build/libvkmesh_io.a
//       build/libvkmesh_base.a -lmeshoptimizer -lzstd -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -o /tmp/mesh_file_bench
//   /tmp/mesh_file_bench mesh.ply [--repeat 3] [--out /tmp] [--ratios 0.5,0.25,0.1]
#include "io/gltf.h"
#include "io/mesh_file.h"
#include "io/mesh_simplify.h"
#include "io/ply.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace vkmesh;

namespace {

double bestMs(int repeat, const std::function<void()>& f) {
    double best = 1e300;
    for (int i = 0; i < repeat; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    return best;
}

}  // namespace

int main(int argc, char** argv) {
    std::string input, ratioList = "0.5,0.25,0.1";
    fs::path out = "/tmp";
    int repeat = 3;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--repeat" && i + 1 < argc) repeat = std::atoi(argv[++i]);
        else if (a == "--out" && i + 1 < argc) out = argv[++i];
        else if (a == "--ratios" && i + 1 < argc) ratioList = argv[++i];
        else input = a;
    }
    if (input.empty()) {
        std::fprintf(stderr, "usage: mesh_file_bench MESH.ply [--repeat 3] [--out /tmp] [--ratios 0.5,0.25,0.1]\n");
        return 2;
    }
    try {
        const Mesh mesh = readPly(input);
        std::printf("%s: %zu vertices, %zu triangles%s%s%s\n", input.c_str(), mesh.positions.size(), mesh.triangles.size(),
                    mesh.normals.empty() ? "" : ", normals", mesh.colors.empty() ? "" : ", colours", mesh.vertexAge.empty() ? "" : ", ages");
        std::printf("%-6s %12s %10s\n", "format", "bytes", "write ms");
        for (const char* ext : {".ply", ".obj", ".glb"}) {
            const fs::path p = out / (std::string("mesh_file_bench") + ext);
            const double ms = bestMs(repeat, [&] { writeMesh(p, mesh); });
            std::printf("%-6s %12ju %10.1f\n", ext, uintmax_t(fs::file_size(p)), ms);
        }
        const fs::path glb = out / "mesh_file_bench.glb";
        std::printf("read .glb back: %.1f ms; read .ply: %.1f ms\n", bestMs(repeat, [&] { readGlb(glb); }),
                    bestMs(repeat, [&] { readPly(out / "mesh_file_bench.ply"); }));
        std::stringstream ratios(ratioList);
        for (std::string r; std::getline(ratios, r, ',');) {
            SimplifyReport report;
            Mesh simple;
            const double ms = bestMs(repeat, [&] { simple = simplifyMesh(mesh, std::stod(r), &report); });
            const fs::path p = out / ("mesh_file_bench_" + r + ".glb");
            writeGlb(p, simple);
            std::printf("simplify %s: %.1f ms, %zu -> %zu triangles, error %.2f mm, .glb %ju bytes\n", r.c_str(), ms,
                        report.trianglesBefore, report.trianglesAfter, 1000 * report.errorMetres, uintmax_t(fs::file_size(p)));
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
