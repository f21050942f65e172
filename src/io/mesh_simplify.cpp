// Mesh simplification with meshoptimizer (io/mesh_simplify.h).
#include "io/mesh_simplify.h"

#include "core/types.h"

#include <meshoptimizer.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace vkmesh {

void checkSimplifyRatio(double ratio, const std::string& what) {
    if (!(ratio > 0 && ratio <= 1)) {
        std::ostringstream s;
        s << what << " " << ratio << ": the fraction of triangles to keep must be in (0, 1]";
        throw Error(s.str());
    }
}

Mesh simplifyMesh(const Mesh& mesh, double ratio, SimplifyReport* report) {
    checkSimplifyRatio(ratio, "simplify ratio");
    const size_t n = mesh.positions.size();
    auto consistent = [&](size_t size) { return size == 0 || size == n; };
    if (!consistent(mesh.normals.size()) || !consistent(mesh.colors.size()) || !consistent(mesh.vertexAge.size()))
        throw Error("cannot simplify: attribute counts differ from the " + std::to_string(n) + " vertices");
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (v >= n) throw Error("cannot simplify: a triangle uses vertex " + std::to_string(v) + " of " + std::to_string(n));
    SimplifyReport r;
    r.ratio = ratio;
    r.trianglesBefore = r.trianglesAfter = mesh.triangles.size();
    if (mesh.triangles.empty()) {
        if (report) *report = r;
        return mesh;
    }
    static_assert(sizeof(Eigen::Vector3f) == 12 && sizeof(mesh.triangles[0]) == 12, "tightly packed positions and triangles");
    const auto* indices = reinterpret_cast<const unsigned int*>(mesh.triangles.data());
    const size_t indexCount = mesh.triangles.size() * 3;

    // Weld by position (the bytes of x, y, z): welded vertex w stands for the first original vertex at its position.
    std::vector<unsigned int> weld(n);
    const size_t welded = meshopt_generateVertexRemap(weld.data(), indices, indexCount, mesh.positions.data(), n, sizeof(Eigen::Vector3f));
    std::vector<uint32_t> original(welded, std::numeric_limits<uint32_t>::max());
    std::vector<Eigen::Vector3f> positions(welded);
    for (size_t i = 0; i < n; ++i) {
        const unsigned int w = weld[i];
        if (w == ~0u || original[w] != std::numeric_limits<uint32_t>::max()) continue;   // unreferenced, or not the first
        original[w] = uint32_t(i);
        positions[w] = mesh.positions[i];
    }
    std::vector<unsigned int> weldedIndices(indexCount);
    meshopt_remapIndexBuffer(weldedIndices.data(), indices, indexCount, weld.data());

    const size_t target = size_t(std::floor(ratio * double(mesh.triangles.size()))) * 3;
    std::vector<unsigned int> kept(indexCount);
    float relativeError = 0;
    kept.resize(meshopt_simplify(kept.data(), weldedIndices.data(), indexCount, &positions[0].x(), welded, sizeof(Eigen::Vector3f),
                                 target, float(kSimplifyMaxRelativeError), 0, &relativeError));
    r.errorMetres = double(relativeError) * meshopt_simplifyScale(&positions[0].x(), welded, sizeof(Eigen::Vector3f));

    // Only the vertices the kept triangles use, in the order they are first used (meshoptimizer's fetch order).
    std::vector<unsigned int> compact(welded);
    const size_t used = meshopt_optimizeVertexFetchRemap(compact.data(), kept.data(), kept.size(), welded);
    Mesh out;
    out.positions.resize(used);
    if (!mesh.normals.empty()) out.normals.resize(used);
    if (!mesh.colors.empty()) out.colors.resize(used);
    if (!mesh.vertexAge.empty()) out.vertexAge.resize(used);
    for (size_t w = 0; w < welded; ++w) {
        const unsigned int c = compact[w];
        if (c == ~0u) continue;
        const uint32_t i = original[w];
        out.positions[c] = mesh.positions[i];
        if (!out.normals.empty()) out.normals[c] = mesh.normals[i];
        if (!out.colors.empty()) out.colors[c] = mesh.colors[i];
        if (!out.vertexAge.empty()) out.vertexAge[c] = mesh.vertexAge[i];
    }
    out.triangles.resize(kept.size() / 3);
    for (size_t t = 0; t < out.triangles.size(); ++t)
        out.triangles[t] = {compact[kept[3 * t]], compact[kept[3 * t + 1]], compact[kept[3 * t + 2]]};
    r.trianglesAfter = out.triangles.size();
    if (report) *report = r;
    return out;
}

}  // namespace vkmesh
