// Tests of the generated marching-cubes tables: conventions, edge masks, per-cube watertightness, agreement of
// neighbouring cubes on every shared face, orientation, and closed 2-manifold meshes from sampled fields.
#include "core/marching_cubes.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

using namespace vkmesh;

namespace {

// The conventions are usable at compile time (the shaders' copies are checked against these).
static_assert(edgeCorners(0)[0] == 0 && edgeCorners(0)[1] == 1);
static_assert(edgeCorners(3)[0] == 6 && edgeCorners(3)[1] == 7);
static_assert(edgeCorners(4)[0] == 0 && edgeCorners(4)[1] == 2);
static_assert(edgeCorners(5)[0] == 1 && edgeCorners(5)[1] == 3);
static_assert(edgeCorners(6)[0] == 4 && edgeCorners(6)[1] == 6);
static_assert(edgeCorners(9)[0] == 1 && edgeCorners(9)[1] == 5);
static_assert(edgeCorners(10)[0] == 2 && edgeCorners(10)[1] == 6);
static_assert(edgeCorners(11)[0] == 3 && edgeCorners(11)[1] == 7);
static_assert(edgeAxis(0) == 0 && edgeAxis(7) == 1 && edgeAxis(8) == 2);
static_assert(edgeOwnerOffset(11) == std::array<int, 3>{1, 1, 0});
static_assert(edgeBetween(5, 7) == 7 && edgeBetween(0, 7) == -1);

Eigen::Vector3f cornerPos(int c) {
    const auto o = cornerOffset(c);
    return Eigen::Vector3f(float(o[0]), float(o[1]), float(o[2]));
}
Eigen::Vector3f edgeMid(int e) {
    const auto c = edgeCorners(e);
    return 0.5f * (cornerPos(c[0]) + cornerPos(c[1]));
}
bool inside(int type, int corner) { return (type >> corner) & 1; }

std::vector<std::array<int, 3>> triangles(int type) {
    const auto& t = marchingCubesTables();
    std::vector<std::array<int, 3>> out;
    for (int i = 0; i < t.triangleCount[type]; ++i)
        out.push_back({t.triangleEdges[type][3 * i], t.triangleEdges[type][3 * i + 1], t.triangleEdges[type][3 * i + 2]});
    return out;
}

// Faces: index 2 * axis + side; the edges lying on a face.
std::vector<int> faceEdges(int axis, int side) {
    std::vector<int> out;
    for (int e = 0; e < kCubeEdges; ++e) {
        const auto c = edgeCorners(e);
        if (cornerCoord(c[0], axis) == side && cornerCoord(c[1], axis) == side) out.push_back(e);
    }
    return out;
}
bool isOnFace(int e, int axis, int side) {
    const auto fe = faceEdges(axis, side);
    return std::find(fe.begin(), fe.end(), e) != fe.end();
}
bool shareFace(int a, int b) {
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            if (isOnFace(a, axis, side) && isOnFace(b, axis, side)) return true;
    return false;
}

// Directed triangle sides (edge id -> edge id) of one cube type.
std::vector<std::pair<int, int>> directedSides(int type) {
    std::vector<std::pair<int, int>> out;
    for (const auto& tri : triangles(type))
        for (int v = 0; v < 3; ++v) out.emplace_back(tri[v], tri[(v + 1) % 3]);
    return out;
}

// The directed triangle sides of `type` that lie on face (axis, side): the boundary of its surface there.
std::set<std::pair<int, int>> faceBoundary(int type, int axis, int side) {
    std::set<std::pair<int, int>> out;
    for (auto [a, b] : directedSides(type))
        if (isOnFace(a, axis, side) && isOnFace(b, axis, side)) out.emplace(a, b);
    return out;
}

}  // namespace

TEST(MarchingCubesConventions, EdgesAreAxisMajorWithLowAndHighCorner) {
    std::set<std::pair<int, int>> seen;
    for (int e = 0; e < kCubeEdges; ++e) {
        const auto [lo, hi] = edgeCorners(e);
        const int axis = edgeAxis(e);
        EXPECT_EQ(axis, e / 4);
        EXPECT_EQ(hi, lo | (1 << axis)) << "edge " << e;
        EXPECT_EQ(cornerCoord(lo, axis), 0) << "edge " << e;
        // The other two coordinates, in increasing axis order, are the bits of k = e & 3.
        const int k = e & 3;
        int bit = 0;
        for (int a = 0; a < 3; ++a) {
            if (a == axis) continue;
            EXPECT_EQ(cornerCoord(lo, a), (k >> bit) & 1) << "edge " << e << " axis " << a;
            ++bit;
        }
        EXPECT_EQ(edgeOwnerOffset(e), cornerOffset(lo));
        EXPECT_EQ(edgeBetween(lo, hi), e);
        EXPECT_EQ(edgeBetween(hi, lo), e);
        seen.emplace(lo, hi);
    }
    EXPECT_EQ(seen.size(), 12u);
    // The cube owns the edges leaving its corner 0: edges 0, 4, 8 have owner offset (0,0,0) and no others.
    for (int e = 0; e < kCubeEdges; ++e)
        EXPECT_EQ(edgeOwnerOffset(e) == (std::array<int, 3>{0, 0, 0}), e == 0 || e == 4 || e == 8) << e;
}

TEST(MarchingCubesConventions, CubeTypeSetsBitForNegativeCorners) {
    float d[8] = {-1, 1, 0, -0.0f, 2, -3, 1e-9f, -1e-9f};
    EXPECT_EQ(cubeType(d), (1 << 0) | (1 << 5) | (1 << 7));  // 0 and -0 count as outside
    for (int t = 0; t < 256; ++t) {
        for (int i = 0; i < 8; ++i) d[i] = inside(t, i) ? -0.5f : 0.25f;
        ASSERT_EQ(cubeType(d), t);
    }
}

TEST(MarchingCubesTables, EmptyAndFullCubesHaveNoTriangles) {
    const auto& t = marchingCubesTables();
    EXPECT_EQ(t.triangleCount[0], 0);
    EXPECT_EQ(t.triangleCount[255], 0);
    EXPECT_EQ(t.edgeMask[0], 0);
    EXPECT_EQ(t.edgeMask[255], 0);
    for (int i = 0; i < 15; ++i) {
        EXPECT_EQ(t.triangleEdges[0][i], -1);
        EXPECT_EQ(t.triangleEdges[255][i], -1);
    }
}

TEST(MarchingCubesTables, EdgeMaskHasExactlyTheSignChangingEdges) {
    const auto& t = marchingCubesTables();
    for (int type = 0; type < 256; ++type) {
        uint16_t expected = 0;
        for (int e = 0; e < kCubeEdges; ++e) {
            const auto c = edgeCorners(e);
            if (inside(type, c[0]) != inside(type, c[1])) expected |= uint16_t(1u << e);
        }
        EXPECT_EQ(t.edgeMask[type], expected) << "type " << type;
    }
}

TEST(MarchingCubesTables, TrianglesUseExactlyTheMaskedEdges) {
    const auto& t = marchingCubesTables();
    for (int type = 0; type < 256; ++type) {
        uint16_t used = 0;
        const int n = t.triangleCount[type];
        ASSERT_LE(n, 5) << "type " << type;
        for (int i = 0; i < 15; ++i) {
            const int e = t.triangleEdges[type][i];
            if (i >= 3 * n) {
                EXPECT_EQ(e, -1) << "type " << type << " padding slot " << i;
                continue;
            }
            ASSERT_GE(e, 0) << "type " << type;
            ASSERT_LT(e, 12) << "type " << type;
            EXPECT_TRUE((t.edgeMask[type] >> e) & 1) << "type " << type << " uses unmasked edge " << e;
            used |= uint16_t(1u << e);
        }
        EXPECT_EQ(used, t.edgeMask[type]) << "type " << type << ": a masked edge has no triangle";
        for (const auto& tri : triangles(type))
            EXPECT_TRUE(tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) << "type " << type;
    }
}

TEST(MarchingCubesTables, AtMostFiveTrianglesPerCube) {
    const auto& t = marchingCubesTables();
    const int m = *std::max_element(std::begin(t.triangleCount), std::end(t.triangleCount));
    EXPECT_EQ(maxTrianglesPerCube(), m);
    EXPECT_LE(m, 5);
    EXPECT_LE(m, kMaxTrianglesPerCube);
    // Every type other than empty and full has at least one crossing loop, hence at least one triangle.
    for (int type = 1; type < 255; ++type) EXPECT_GE(t.triangleCount[type], 1) << "type " << type;
}

TEST(MarchingCubesTables, SingleCornerAndHalfCubeCases) {
    const auto& t = marchingCubesTables();
    for (int c = 0; c < 8; ++c) {
        EXPECT_EQ(t.triangleCount[1 << c], 1) << "single inside corner " << c;
        EXPECT_EQ(t.triangleCount[255 ^ (1 << c)], 1) << "single outside corner " << c;
    }
    for (int axis = 0; axis < 3; ++axis) {
        int low = 0;  // corners with coordinate `axis` = 0
        for (int c = 0; c < 8; ++c)
            if (!cornerCoord(c, axis)) low |= 1 << c;
        EXPECT_EQ(t.triangleCount[low], 2) << "half cube " << low;
        EXPECT_EQ(t.triangleCount[255 ^ low], 2) << "half cube " << (255 ^ low);
    }
    EXPECT_EQ(t.triangleCount[0x0F], 2);
    // Two inside corners on an edge: a quad, 2 triangles.
    EXPECT_EQ(t.triangleCount[0x03], 2);
}

// Inside one cube, every triangle side joining two edges that do not share a cube face is interior to the
// surface: it is used exactly twice, once in each direction. Sides joining two edges of one face lie on the
// cube boundary and are used exactly once; on each face they cover every crossing edge of that face once.
TEST(MarchingCubesTables, EveryCubeSurfaceIsWatertightInside) {
    for (int type = 0; type < 256; ++type) {
        std::map<std::pair<int, int>, int> count;
        for (auto s : directedSides(type)) ++count[s];
        for (auto [s, n] : count) {
            auto [a, b] = s;
            const int rev = count.count({b, a}) ? count.at({b, a}) : 0;
            if (shareFace(a, b)) {
                EXPECT_EQ(n, 1) << "type " << type << " face side " << a << "->" << b;
                EXPECT_EQ(rev, 0) << "type " << type << " face side " << a << "->" << b << " used both ways";
            } else {
                EXPECT_EQ(n, 1) << "type " << type << " interior side " << a << "->" << b;
                EXPECT_EQ(rev, 1) << "type " << type << " interior side " << a << "->" << b << " not matched";
            }
        }
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                std::map<int, int> touched;
                for (auto [a, b] : faceBoundary(type, axis, side)) {
                    ++touched[a];
                    ++touched[b];
                }
                for (int e : faceEdges(axis, side)) {
                    const auto c = edgeCorners(e);
                    const int expected = inside(type, c[0]) != inside(type, c[1]) ? 1 : 0;
                    EXPECT_EQ(touched[e], expected)
                        << "type " << type << " face " << axis << "/" << side << " edge " << e;
                }
            }
    }
}

// The boundary segments on a face depend only on that face's 4 corner signs.
TEST(MarchingCubesTables, FaceBoundaryDependsOnlyOnFaceCorners) {
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            int faceMask = 0;
            for (int c = 0; c < 8; ++c)
                if (cornerCoord(c, axis) == side) faceMask |= 1 << c;
            std::map<int, std::set<std::pair<int, int>>> byFaceSigns;
            for (int type = 0; type < 256; ++type) {
                const auto b = faceBoundary(type, axis, side);
                auto [it, fresh] = byFaceSigns.emplace(type & faceMask, b);
                if (!fresh) {
                    EXPECT_EQ(it->second, b) << "type " << type << " face " << axis << "/" << side;
                }
            }
        }
}

// Two cubes sharing a face (A below, B above along `axis`), for every pair of types that agree on the 4
// shared corners: A's boundary segments on the shared face, mapped onto B's edges, are B's reversed. With
// the per-cube watertightness above, this makes the whole mesh closed and consistently oriented.
TEST(MarchingCubesTables, NeighbouringCubesAgreeOnEverySharedFace) {
    int pairsChecked = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const int bit = 1 << axis;
        for (int ta = 0; ta < 256; ++ta) {
            const auto bA = faceBoundary(ta, axis, 1);
            for (int tb = 0; tb < 256; ++tb) {
                bool agree = true;
                for (int c = 0; c < 8; ++c)
                    if ((c & bit) && inside(ta, c) != inside(tb, c ^ bit)) agree = false;
                if (!agree) continue;
                auto mapEdge = [&](int e) {
                    const auto c = edgeCorners(e);
                    return edgeBetween(c[0] ^ bit, c[1] ^ bit);
                };
                std::set<std::pair<int, int>> mapped;
                for (auto [a, b] : bA) mapped.emplace(mapEdge(b), mapEdge(a));  // reversed
                EXPECT_EQ(mapped, faceBoundary(tb, axis, 0)) << "axis " << axis << " A " << ta << " B " << tb;
                ++pairsChecked;
            }
        }
    }
    EXPECT_EQ(pairsChecked, 3 * 16 * 16 * 16);
}

// With vertices at edge midpoints, each triangle's normal (v1-v0)x(v2-v0) points from inside to outside.
TEST(MarchingCubesTables, OrientationSingleCornerAndPlanarCases) {
    auto normalsOf = [](int type) {
        std::vector<Eigen::Vector3f> out;
        for (const auto& tri : triangles(type)) {
            const Eigen::Vector3f a = edgeMid(tri[0]), b = edgeMid(tri[1]), c = edgeMid(tri[2]);
            out.push_back((b - a).cross(c - a));
        }
        return out;
    };
    const Eigen::Vector3f centre(0.5f, 0.5f, 0.5f);
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3f outward = centre - cornerPos(c);  // from the lone inside corner into the cube
        for (const auto& n : normalsOf(1 << c)) EXPECT_GT(n.normalized().dot(outward.normalized()), 0.99f) << c;
        // Lone outside corner: the normal points toward it.
        for (const auto& n : normalsOf(255 ^ (1 << c)))
            EXPECT_GT(n.normalized().dot(-outward.normalized()), 0.99f) << c;
    }
    for (int axis = 0; axis < 3; ++axis) {
        int low = 0;
        for (int c = 0; c < 8; ++c)
            if (!cornerCoord(c, axis)) low |= 1 << c;
        Eigen::Vector3f up = Eigen::Vector3f::Zero();
        up[axis] = 1.0f;
        const auto nLow = normalsOf(low);  // inside below: the normal points up
        ASSERT_EQ(nLow.size(), 2u);
        for (const auto& n : nLow) EXPECT_GT(n.normalized().dot(up), 0.999f) << "type " << low;
        const auto nHigh = normalsOf(255 ^ low);
        ASSERT_EQ(nHigh.size(), 2u);
        for (const auto& n : nHigh) EXPECT_GT(n.normalized().dot(-up), 0.999f) << "type " << (255 ^ low);
    }
}

// General orientation: every triangle's normal agrees with the gradient of the trilinear interpolant of the
// corner signs (+1 outside, -1 inside) at the triangle's centroid, and no triangle is degenerate.
TEST(MarchingCubesTables, OrientationAgreesWithTrilinearGradient) {
    for (int type = 0; type < 256; ++type)
        for (const auto& tri : triangles(type)) {
            const Eigen::Vector3f a = edgeMid(tri[0]), b = edgeMid(tri[1]), c = edgeMid(tri[2]);
            const Eigen::Vector3f n = (b - a).cross(c - a);
            const Eigen::Vector3f m = (a + b + c) / 3.0f;
            Eigen::Vector3f g = Eigen::Vector3f::Zero();
            for (int k = 0; k < 8; ++k) {
                const float v = inside(type, k) ? -1.0f : 1.0f;
                for (int d = 0; d < 3; ++d) {
                    float w = cornerCoord(k, d) ? 1.0f : -1.0f;
                    for (int d2 = 0; d2 < 3; ++d2)
                        if (d2 != d) w *= cornerCoord(k, d2) ? m[d2] : 1.0f - m[d2];
                    g[d] += v * w;
                }
            }
            EXPECT_GT(n.norm(), 0.1f) << "degenerate triangle in type " << type;
            EXPECT_GT(n.dot(g), 0.0f) << "type " << type << " triangle " << tri[0] << "," << tri[1] << "," << tri[2];
        }
}

// --- CPU marching cubes over a sampled grid, used by the integration tests ---
namespace {

struct GridMesh {
    std::vector<Eigen::Vector3f> vertices;
    std::vector<std::array<int, 3>> triangles;
    std::set<int> typesSeen;
};

// Samples f at the n^3 integer points, then meshes every cube with the tables. A vertex is shared per grid
// edge through a map keyed by the global edge id (owner cube's linear index * 3 + axis).
GridMesh marchGrid(int n, const std::function<float(int, int, int)>& f) {
    std::vector<float> d(size_t(n) * n * n);
    auto idx = [n](int x, int y, int z) { return (size_t(z) * n + y) * n + x; };
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) d[idx(x, y, z)] = f(x, y, z);
    const auto& t = marchingCubesTables();
    GridMesh mesh;
    std::unordered_map<size_t, int> vertexOfEdge;
    for (int z = 0; z + 1 < n; ++z)
        for (int y = 0; y + 1 < n; ++y)
            for (int x = 0; x + 1 < n; ++x) {
                float cd[8];
                for (int c = 0; c < 8; ++c) {
                    const auto o = cornerOffset(c);
                    cd[c] = d[idx(x + o[0], y + o[1], z + o[2])];
                }
                const int type = cubeType(cd);
                if (!t.triangleCount[type]) continue;
                mesh.typesSeen.insert(type);
                int vert[12];
                for (int e = 0; e < kCubeEdges; ++e) {
                    if (!((t.edgeMask[type] >> e) & 1)) continue;
                    const auto own = edgeOwnerOffset(e);
                    const size_t key = idx(x + own[0], y + own[1], z + own[2]) * 3 + size_t(edgeAxis(e));
                    auto [it, fresh] = vertexOfEdge.emplace(key, int(mesh.vertices.size()));
                    if (fresh) {
                        const auto [c0, c1] = edgeCorners(e);
                        const float s = cd[c0] / (cd[c0] - cd[c1]);
                        const Eigen::Vector3f p0 = Eigen::Vector3f(float(x), float(y), float(z)) + cornerPos(c0);
                        const Eigen::Vector3f p1 = Eigen::Vector3f(float(x), float(y), float(z)) + cornerPos(c1);
                        mesh.vertices.push_back(p0 + s * (p1 - p0));
                    }
                    vert[e] = it->second;
                }
                for (int i = 0; i < t.triangleCount[type]; ++i)
                    mesh.triangles.push_back({vert[t.triangleEdges[type][3 * i]], vert[t.triangleEdges[type][3 * i + 1]],
                                              vert[t.triangleEdges[type][3 * i + 2]]});
            }
    return mesh;
}

// Checks that the mesh is a closed, consistently oriented 2-manifold; returns V - E + F.
int checkClosedManifold(const GridMesh& m) {
    std::map<std::pair<int, int>, int> directed;
    for (const auto& tri : m.triangles) {
        EXPECT_TRUE(tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) << "degenerate triangle";
        for (int v = 0; v < 3; ++v) ++directed[{tri[v], tri[(v + 1) % 3]}];
    }
    size_t undirected = 0;
    for (auto [s, n] : directed) {
        EXPECT_EQ(n, 1) << "side " << s.first << "->" << s.second << " used " << n << " times in one direction";
        const auto rev = directed.find({s.second, s.first});
        EXPECT_TRUE(rev != directed.end()) << "side " << s.first << "->" << s.second << " has no opposite side";
        if (s.first < s.second) ++undirected;
    }
    EXPECT_EQ(directed.size(), 2 * undirected);  // every mesh edge in exactly 2 triangles, opposite directions

    // Vertex manifoldness: the triangles around each vertex form one cycle (next around v: a->b gives b).
    std::vector<std::map<int, int>> ring(m.vertices.size());
    for (const auto& tri : m.triangles)
        for (int v = 0; v < 3; ++v) ring[tri[v]][tri[(v + 1) % 3]] = tri[(v + 2) % 3];
    for (size_t v = 0; v < ring.size(); ++v) {
        if (ring[v].empty()) {
            ADD_FAILURE() << "unused vertex " << v;
            continue;
        }
        const int start = ring[v].begin()->first;
        int cur = start;
        size_t steps = 0;
        do {
            auto it = ring[v].find(cur);
            if (it == ring[v].end()) break;
            cur = it->second;
            ++steps;
        } while (cur != start && steps <= ring[v].size());
        EXPECT_EQ(steps, ring[v].size()) << "vertex " << v << " is not a single fan";
    }
    return int(m.vertices.size()) - int(undirected) + int(m.triangles.size());
}

}  // namespace

TEST(MarchingCubesIntegration, SphereGivesClosedManifoldOnTheSurface) {
    const int n = 24;
    const Eigen::Vector3f centre(11.3f, 11.62f, 11.47f);
    const float radius = 8.2f;
    const auto mesh = marchGrid(n, [&](int x, int y, int z) {
        return (Eigen::Vector3f(float(x), float(y), float(z)) - centre).norm() - radius;
    });
    ASSERT_GT(mesh.triangles.size(), 500u);
    EXPECT_EQ(checkClosedManifold(mesh), 2) << "Euler characteristic of a sphere";
    float worst = 0.0f;
    for (const auto& p : mesh.vertices) worst = std::max(worst, std::abs((p - centre).norm() - radius));
    EXPECT_LT(worst, 0.5f);
    // Outward orientation: the signed volume enclosed is positive and close to the sphere's.
    double volume = 0.0;
    for (const auto& tri : mesh.triangles) {
        const Eigen::Vector3d a = (mesh.vertices[tri[0]] - centre).cast<double>();
        const Eigen::Vector3d b = (mesh.vertices[tri[1]] - centre).cast<double>();
        const Eigen::Vector3d c = (mesh.vertices[tri[2]] - centre).cast<double>();
        volume += a.dot(b.cross(c)) / 6.0;
    }
    const double expected = 4.0 / 3.0 * M_PI * radius * radius * radius;
    EXPECT_NEAR(volume, expected, 0.03 * expected);
    for (const auto& tri : mesh.triangles) {
        const Eigen::Vector3f nrm = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                        .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
        const Eigen::Vector3f radial = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0f - centre;
        EXPECT_GT(nrm.dot(radial), 0.0f) << "inward-facing triangle";
    }
}

TEST(MarchingCubesIntegration, TwoTouchingSpheresStayManifold) {
    // Two spheres almost touching: the neck region produces ambiguous faces.
    const int n = 24;
    const Eigen::Vector3f c1(7.4f, 11.5f, 11.5f), c2(16.1f, 11.3f, 11.7f);
    const auto mesh = marchGrid(n, [&](int x, int y, int z) {
        const Eigen::Vector3f p{float(x), float(y), float(z)};
        return std::min((p - c1).norm() - 4.3f, (p - c2).norm() - 4.3f);
    });
    checkClosedManifold(mesh);
}

// Random signs inside a grid whose border is outside: every cube type and every ambiguous face combination
// shows up, and the mesh must still be a closed, consistently oriented 2-manifold.
TEST(MarchingCubesIntegration, RandomFieldGivesClosedManifold) {
    const int n = 20;
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> values(size_t(n) * n * n);
    for (auto& v : values) {
        v = u(rng);
        if (v == 0.0f) v = 0.5f;
    }
    const auto mesh = marchGrid(n, [&](int x, int y, int z) {
        if (x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1) return 1.0f;
        return values[(size_t(z) * n + y) * n + x];
    });
    EXPECT_EQ(mesh.typesSeen.size(), 254u) << "every non-empty type should appear";
    checkClosedManifold(mesh);
}
