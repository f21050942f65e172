// The mesh checks the mesh tests rely on: topology of small hand-made meshes (closed, open, misoriented,
// non-manifold, several components), duplicate and unreferenced vertices, the canonical triangle form, welding.
#include "core/mesh_analysis.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

using namespace vkmesh;

namespace {

// A tetrahedron, every face counter-clockwise seen from outside.
Mesh tetrahedron(const Eigen::Vector3f& offset = Eigen::Vector3f::Zero()) {
    Mesh m;
    m.positions = {offset + Eigen::Vector3f(0, 0, 0), offset + Eigen::Vector3f(1, 0, 0), offset + Eigen::Vector3f(0, 1, 0),
                   offset + Eigen::Vector3f(0, 0, 1)};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
}

std::vector<Eigen::Vector3f> soupOf(const Mesh& m) {
    std::vector<Eigen::Vector3f> soup;
    for (const auto& t : m.triangles)
        for (uint32_t v : t) soup.push_back(m.positions[v]);
    return soup;
}

Mesh append(Mesh a, const Mesh& b) {
    const uint32_t base = uint32_t(a.positions.size());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (auto t : b.triangles) a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return a;
}

TEST(MeshAnalysis, TetrahedronIsClosedWithEulerCharacteristicTwo) {
    const Mesh m = tetrahedron();
    // Every face's normal points away from the centroid (the test mesh itself is oriented outward).
    const Eigen::Vector3f centroid(0.25f, 0.25f, 0.25f);
    for (const auto& t : m.triangles) {
        const Eigen::Vector3f n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
        EXPECT_GT(n.dot(m.positions[t[0]] - centroid), 0.0f);
    }
    const TopologyReport r = analyzeTopology(m);
    EXPECT_EQ(r.vertices, 4u);
    EXPECT_EQ(r.edges, 6u);
    EXPECT_EQ(r.faces, 4u);
    EXPECT_EQ(r.boundaryEdges, 0u);
    EXPECT_EQ(r.nonManifoldEdges, 0u);
    EXPECT_EQ(r.misorientedEdges, 0u);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.eulerCharacteristic, 2);
    EXPECT_TRUE(r.closedManifold());
    EXPECT_EQ(countDuplicatePositions(m), 0u);
    EXPECT_EQ(countUnreferencedVertices(m), 0u);
}

TEST(MeshAnalysis, RemovingAFaceLeavesThreeBoundaryEdges) {
    Mesh m = tetrahedron();
    m.triangles.pop_back();
    const TopologyReport r = analyzeTopology(m);
    EXPECT_EQ(r.boundaryEdges, 3u);
    EXPECT_EQ(r.misorientedEdges, 0u);
    EXPECT_EQ(r.eulerCharacteristic, 1);
    EXPECT_FALSE(r.closedManifold());
}

TEST(MeshAnalysis, FlippingAFaceMisorientsItsThreeEdges) {
    Mesh m = tetrahedron();
    std::swap(m.triangles[3][1], m.triangles[3][2]);
    const TopologyReport r = analyzeTopology(m);
    EXPECT_EQ(r.misorientedEdges, 3u);
    EXPECT_EQ(r.boundaryEdges, 0u);
    EXPECT_FALSE(r.closedManifold());
}

TEST(MeshAnalysis, NonManifoldEdgesAndComponents) {
    Mesh m = tetrahedron();
    m.positions.emplace_back(1, 1, -1);
    m.triangles.push_back({0, 1, 4});  // a fin on edge 0-1: used 3 times
    TopologyReport r = analyzeTopology(m);
    EXPECT_EQ(r.nonManifoldEdges, 1u);
    EXPECT_EQ(r.boundaryEdges, 2u);
    EXPECT_FALSE(r.closedManifold());

    const Mesh two = append(tetrahedron(), tetrahedron(Eigen::Vector3f(5, 0, 0)));
    r = analyzeTopology(two);
    EXPECT_EQ(r.components, 2u);
    EXPECT_EQ(r.eulerCharacteristic, 4);
    EXPECT_TRUE(r.closedManifold());

    // Two tetrahedra sharing only a vertex are still two components (faces connect through edges).
    Mesh touching = tetrahedron();
    touching.positions.insert(touching.positions.end(), {Eigen::Vector3f(-1, 0, 0), Eigen::Vector3f(0, -1, 0), Eigen::Vector3f(0, 0, -1)});
    touching.triangles.insert(touching.triangles.end(), {{0, 4, 5}, {0, 5, 6}, {0, 6, 4}, {4, 6, 5}});
    EXPECT_EQ(analyzeTopology(touching).components, 2u);
}

TEST(MeshAnalysis, DuplicateAndUnreferencedVertices) {
    Mesh m = tetrahedron();
    m.positions.push_back(m.positions[2]);        // a copy of vertex 2, unused
    m.positions.push_back(m.positions[2]);        // another
    m.positions.emplace_back(7, 7, 7);            // unique, unused
    m.positions.emplace_back(-0.0f, 0.0f, 0.0f);  // equal to vertex 0 (-0 == 0), unused
    EXPECT_EQ(countDuplicatePositions(m), 3u);
    EXPECT_EQ(countUnreferencedVertices(m), 4u);
    m.triangles[3] = {1, 4, 3};  // use a copy instead of vertex 2: vertex 2 is still used by other faces
    EXPECT_EQ(countUnreferencedVertices(m), 3u);
    // The topology is by index: the copy splits edges, the tetrahedron is no longer closed.
    EXPECT_FALSE(analyzeTopology(m).closedManifold());
}

TEST(MeshAnalysis, CanonicalFormIgnoresOrderAndRotationButNotOrientation) {
    const Mesh m = tetrahedron(Eigen::Vector3f(0.1f, -2.0f, 3.0f));
    const auto reference = canonicalTriangles(m);
    ASSERT_EQ(reference.size(), 4u);
    EXPECT_EQ(countTriangleMismatches(reference, canonicalTriangles(soupOf(m))), 0u);

    // Rotating the vertex list of every triangle and reversing the triangle order changes nothing.
    Mesh rotated = m;
    for (auto& t : rotated.triangles) t = {t[1], t[2], t[0]};
    std::reverse(rotated.triangles.begin(), rotated.triangles.end());
    EXPECT_EQ(canonicalTriangles(rotated), reference);
    EXPECT_EQ(countTriangleMismatches(reference, canonicalTriangles(rotated), 0), 0u);

    // Flipping one triangle is a difference.
    Mesh flipped = m;
    std::swap(flipped.triangles[2][0], flipped.triangles[2][1]);
    EXPECT_GE(countTriangleMismatches(reference, canonicalTriangles(flipped)), 1u);

    // A missing triangle counts.
    Mesh fewer = m;
    fewer.triangles.pop_back();
    EXPECT_GE(countTriangleMismatches(reference, canonicalTriangles(fewer)), 1u);

    // Positions within the tolerance (in quanta) match, beyond it they do not.
    auto soup = soupOf(m);
    soup[4].x() += 0.6e-6f;  // about one quantum of 1e-6
    EXPECT_EQ(countTriangleMismatches(reference, canonicalTriangles(soup), 1), 0u);
    soup[4].x() += 5e-6f;
    EXPECT_EQ(countTriangleMismatches(reference, canonicalTriangles(soup), 1), 1u);
}

TEST(MeshAnalysis, WeldMergesExactlyEqualPositionsOnly) {
    const Mesh m = tetrahedron(Eigen::Vector3f(0.5f, 0.25f, -1.0f));
    auto soup = soupOf(m);
    ASSERT_EQ(soup.size(), 12u);
    const Mesh welded = weldExactPositions(soup);
    EXPECT_EQ(welded.positions.size(), 4u);
    ASSERT_EQ(welded.triangles.size(), 4u);
    EXPECT_TRUE(analyzeTopology(welded).closedManifold());
    EXPECT_EQ(canonicalTriangles(welded), canonicalTriangles(m));

    // A position one ulp off is not merged: the weld is exact.
    soup[11] = Eigen::Vector3f(std::nextafter(soup[11].x(), 10.0f), soup[11].y(), soup[11].z());
    const Mesh apart = weldExactPositions(soup);
    EXPECT_EQ(apart.positions.size(), 5u);
    EXPECT_FALSE(analyzeTopology(apart).closedManifold());
}

}  // namespace
