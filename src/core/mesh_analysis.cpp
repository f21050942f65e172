#include "core/mesh_analysis.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numeric>
#include <utility>

namespace vkmesh {
namespace {

// Lexicographic order of positions (x, then y, then z), by float <: two positions are equivalent iff they are
// exactly equal (0.0 and -0.0 included).
struct PositionLess {
    bool operator()(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const {
        if (a.x() != b.x()) return a.x() < b.x();
        if (a.y() != b.y()) return a.y() < b.y();
        return a.z() < b.z();
    }
};

// Union-find over triangle indices, for components.
struct DisjointSets {
    std::vector<size_t> parent;
    explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), size_t(0)); }
    size_t find(size_t i) {
        while (parent[i] != i) {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        return i;
    }
    void unite(size_t a, size_t b) { parent[find(a)] = find(b); }
};

}  // namespace

size_t countDuplicatePositions(const Mesh& mesh) {
    std::map<Eigen::Vector3f, size_t, PositionLess> seen;
    size_t duplicates = 0;
    for (const Eigen::Vector3f& p : mesh.positions)
        if (!seen.emplace(p, 0).second) ++duplicates;
    return duplicates;
}

size_t countUnreferencedVertices(const Mesh& mesh) {
    std::vector<char> used(mesh.positions.size(), 0);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (v < used.size()) used[v] = 1;
    return size_t(std::count(used.begin(), used.end(), 0));
}

TopologyReport analyzeTopology(const Mesh& mesh) {
    struct EdgeUse {
        size_t uses = 0;
        size_t forward = 0;  // uses traversing it from the smaller index to the larger
        size_t firstFace = 0;
    };
    TopologyReport report;
    report.faces = mesh.triangles.size();
    std::map<std::pair<uint32_t, uint32_t>, EdgeUse> edges;
    DisjointSets faces(mesh.triangles.size());
    std::vector<char> used(mesh.positions.size(), 0);
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        for (int i = 0; i < 3; ++i) {
            uint32_t a = t[i], b = t[(i + 1) % 3];
            if (a < used.size()) used[a] = 1;
            EdgeUse& e = edges[{std::min(a, b), std::max(a, b)}];
            if (e.uses == 0) e.firstFace = f;
            else faces.unite(f, e.firstFace);
            ++e.uses;
            if (a < b) ++e.forward;
        }
    }
    report.vertices = size_t(std::count(used.begin(), used.end(), 1));
    report.edges = edges.size();
    for (const auto& [key, e] : edges) {
        if (e.uses == 1) ++report.boundaryEdges;
        if (e.uses > 2) ++report.nonManifoldEdges;
        if (e.uses == 2 && e.forward != 1) ++report.misorientedEdges;
    }
    for (size_t f = 0; f < mesh.triangles.size(); ++f)
        if (faces.find(f) == f) ++report.components;
    report.eulerCharacteristic = long(report.vertices) - long(report.edges) + long(report.faces);
    return report;
}

std::vector<CanonicalTriangle> canonicalTriangles(const std::vector<Eigen::Vector3f>& soup, double quantum) {
    std::vector<CanonicalTriangle> out;
    out.reserve(soup.size() / 3);
    for (size_t t = 0; t + 2 < soup.size(); t += 3) {
        std::array<std::array<int64_t, 3>, 3> v;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) v[i][k] = std::llround(double(soup[t + i][k]) / quantum);
        const int first = int(std::min_element(v.begin(), v.end()) - v.begin());
        CanonicalTriangle tri;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) tri[i * 3 + k] = v[(first + i) % 3][k];
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<CanonicalTriangle> canonicalTriangles(const Mesh& mesh, double quantum) {
    std::vector<Eigen::Vector3f> soup;
    soup.reserve(mesh.triangles.size() * 3);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) soup.push_back(mesh.positions.at(v));
    return canonicalTriangles(soup, quantum);
}

size_t countTriangleMismatches(const std::vector<CanonicalTriangle>& a, const std::vector<CanonicalTriangle>& b,
                               int64_t tolerance) {
    const size_t common = std::min(a.size(), b.size());
    size_t mismatches = std::max(a.size(), b.size()) - common;
    for (size_t i = 0; i < common; ++i) {
        for (int k = 0; k < 9; ++k) {
            if (std::llabs(a[i][k] - b[i][k]) > tolerance) {
                ++mismatches;
                break;
            }
        }
    }
    return mismatches;
}

Mesh weldExactPositions(const std::vector<Eigen::Vector3f>& soup) {
    Mesh mesh;
    std::map<Eigen::Vector3f, uint32_t, PositionLess> index;
    auto vertexOf = [&](const Eigen::Vector3f& p) {
        auto [it, inserted] = index.emplace(p, uint32_t(mesh.positions.size()));
        if (inserted) mesh.positions.push_back(p);
        return it->second;
    };
    for (size_t t = 0; t + 2 < soup.size(); t += 3)
        mesh.triangles.push_back({vertexOf(soup[t]), vertexOf(soup[t + 1]), vertexOf(soup[t + 2])});
    return mesh;
}

RegularityReport triangleRegularity(const Mesh& mesh, double minAngleDegrees) {
    const double cosLimit = std::cos(minAngleDegrees * 3.14159265358979323846 / 180.0);
    RegularityReport report;
    for (const auto& t : mesh.triangles) {
        ++report.triangles;
        bool sliver = false;
        for (int k = 0; k < 3 && !sliver; ++k) {
            const Eigen::Vector3d p = mesh.positions[t[k]].cast<double>();
            const Eigen::Vector3d u = mesh.positions[t[(k + 1) % 3]].cast<double>() - p;
            const Eigen::Vector3d w = mesh.positions[t[(k + 2) % 3]].cast<double>() - p;
            const double lengths = u.norm() * w.norm();
            // The angle at p is below the limit when its cosine is above the limit's.
            sliver = lengths == 0.0 || u.dot(w) / lengths > cosLimit;
        }
        if (sliver) ++report.slivers;
    }
    return report;
}

}  // namespace vkmesh
