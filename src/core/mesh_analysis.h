// Checks on triangle meshes, shared by the CPU and GPU tests of the mesh stages: duplicate and unreferenced
// vertices, topology (boundary, non-manifold and misoriented edges, components, Euler characteristic), an
// order-independent canonical form of a triangle set for comparing two meshes, and welding a triangle soup
// into an indexed mesh.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace vkmesh {

// Vertices whose position is exactly equal (float ==) to that of an earlier vertex.
size_t countDuplicatePositions(const Mesh& mesh);

// Vertices no triangle uses.
size_t countUnreferencedVertices(const Mesh& mesh);

// Topology of an indexed mesh. Edges are unordered pairs of vertex indices (positions are not looked at).
struct TopologyReport {
    size_t vertices = 0;          // vertices used by at least one triangle
    size_t edges = 0;             // distinct edges
    size_t faces = 0;             // triangles
    size_t boundaryEdges = 0;     // edges used by exactly 1 triangle
    size_t nonManifoldEdges = 0;  // edges used by more than 2 triangles
    size_t misorientedEdges = 0;  // edges used by exactly 2 triangles that traverse it in the same direction
    size_t components = 0;        // connected components of triangles sharing an edge
    long eulerCharacteristic = 0; // vertices - edges + faces

    // Some triangles, every edge shared by exactly 2 triangles traversing it in opposite directions.
    bool closedManifold() const {
        return faces > 0 && boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0;
    }
};

TopologyReport analyzeTopology(const Mesh& mesh);

// Canonical form of a triangle set, independent of triangle order and of where each triangle's vertex list
// starts: every coordinate is quantised to llround(x / quantum), each triangle is rotated (orientation kept)
// to start at its lexicographically smallest quantised vertex, and the triangles are sorted. A triangle is
// 9 integers: x0 y0 z0 x1 y1 z1 x2 y2 z2.
using CanonicalTriangle = std::array<int64_t, 9>;
std::vector<CanonicalTriangle> canonicalTriangles(const std::vector<Eigen::Vector3f>& soup, double quantum = 1e-6);
// The same for an indexed mesh (its triangles expanded to positions).
std::vector<CanonicalTriangle> canonicalTriangles(const Mesh& mesh, double quantum = 1e-6);

// Compares two canonical lists entry by entry: |size difference| + the entries (up to the shorter size) in
// which some coordinate differs by more than `tolerance` quanta. 0 means the same triangles.
size_t countTriangleMismatches(const std::vector<CanonicalTriangle>& a, const std::vector<CanonicalTriangle>& b,
                               int64_t tolerance = 1);

// A triangle soup (3 consecutive positions per triangle) as an indexed mesh: exactly equal positions become one
// vertex (numbered in order of first appearance), triangles keep their order and orientation.
Mesh weldExactPositions(const std::vector<Eigen::Vector3f>& soup);

// How regular a mesh's triangles are (paper §V.F, Fig. 7: corners whose TSDF is near zero flip cube types
// and leave thin, irregular triangles). A triangle is a sliver when its smallest angle is below
// `minAngleDegrees` (degenerate triangles included).
struct RegularityReport {
    size_t triangles = 0;
    size_t slivers = 0;
    double sliverShare() const { return triangles ? double(slivers) / double(triangles) : 0.0; }
};
RegularityReport triangleRegularity(const Mesh& mesh, double minAngleDegrees = 10.0);

}  // namespace vkmesh
