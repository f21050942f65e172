#include "core/marching_cubes.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace vkmesh {
namespace {

// A cube face: the corners whose coordinate `axis` equals `side`.
struct Face {
    int axis = 0, side = 0;
    int edges[4] = {};  // the 4 cube edges lying on the face
    Eigen::Vector3f outward = Eigen::Vector3f::Zero();
};

Eigen::Vector3f cornerPos(int c) {
    const auto o = cornerOffset(c);
    return Eigen::Vector3f(float(o[0]), float(o[1]), float(o[2]));
}

Eigen::Vector3f edgeMid(int e) {
    const auto c = edgeCorners(e);
    return 0.5f * (cornerPos(c[0]) + cornerPos(c[1]));
}

std::array<Face, 6> makeFaces() {
    std::array<Face, 6> faces;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            Face& f = faces[axis * 2 + side];
            f.axis = axis;
            f.side = side;
            int n = 0;
            for (int e = 0; e < kCubeEdges; ++e) {
                if (edgeAxis(e) == axis) continue;
                if (cornerCoord(edgeCorners(e)[0], axis) == side) f.edges[n++] = e;
            }
            f.outward = Eigen::Vector3f::Zero();
            f.outward[axis] = side ? 1.0f : -1.0f;
        }
    return faces;
}

bool onFace(const Face& f, int e) { return std::find(std::begin(f.edges), std::end(f.edges), e) != std::end(f.edges); }

[[noreturn]] void fail(const std::string& what, int type) {
    throw std::logic_error("marching cubes table generation: " + what + " (type " + std::to_string(type) + ")");
}

// Oriented segments (from edge, to edge) of the iso-line on one face, by a rule that depends only on the
// face's 4 corner signs: two crossings are joined; on an ambiguous face (4 crossings, inside corners on a
// diagonal) each inside corner is cut off by its own segment, i.e. the inside corners are kept apart.
// Orientation: seen from outside the cube, positive (free) space is on the left of the segment.
void faceSegments(const Face& f, int type, std::vector<std::pair<int, int>>& out) {
    auto inside = [type](int c) { return (type >> c) & 1; };
    std::vector<int> crossing;
    for (int e : f.edges) {
        const auto c = edgeCorners(e);
        if (inside(c[0]) != inside(c[1])) crossing.push_back(e);
    }
    std::vector<std::pair<int, int>> pairs;
    if (crossing.size() == 2) {
        pairs.emplace_back(crossing[0], crossing[1]);
    } else if (crossing.size() == 4) {
        // Pair the two face edges around each inside corner.
        for (int c = 0; c < kCubeCorners; ++c) {
            if (cornerCoord(c, f.axis) != f.side || !inside(c)) continue;
            int found[2], n = 0;
            for (int e : f.edges) {
                const auto ec = edgeCorners(e);
                if (ec[0] == c || ec[1] == c) found[n++] = e;
            }
            if (n != 2) fail("face corner without 2 face edges", type);
            pairs.emplace_back(found[0], found[1]);
        }
        if (pairs.size() != 2) fail("ambiguous face without 2 inside corners", type);
    } else if (!crossing.empty()) {
        fail("odd number of crossings on a face", type);
    }
    for (auto [a, b] : pairs) {
        const Eigen::Vector3f p = edgeMid(a), q = edgeMid(b);
        const auto ac = edgeCorners(a);
        const Eigen::Vector3f neg = cornerPos(inside(ac[0]) ? ac[0] : ac[1]);
        const float s = f.outward.cross(q - p).dot(neg - p);
        if (s == 0.0f) fail("degenerate face segment", type);
        // The left of p->q (seen from outside) is outward x (q - p): the inside corner must be on the right.
        if (s < 0.0f) out.emplace_back(a, b);
        else out.emplace_back(b, a);
    }
}

// Shape cost of a triangle: 0 for equilateral, growing without bound toward a sliver.
float triangleCost(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                   const Eigen::Vector3f& loopNormal) {
    const Eigen::Vector3f n = (b - a).cross(c - a);
    const float area2 = n.norm();  // twice the area
    const float sumSq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    float cost = area2 > 1e-9f ? sumSq / (2.0f * std::sqrt(3.0f) * area2) - 1.0f : 1e6f;
    if (n.dot(loopNormal) <= 0.0f) cost += 1e6f;  // a triangle folded against its loop
    return cost;
}

// Triangulates one closed oriented loop of edge ids into loop.size() - 2 triangles, keeping the loop's
// orientation, never using a diagonal between two edges of one cube face (it would lie on the face, where
// the neighbouring cube has no matching edge), and minimising the summed shape cost.
void triangulateLoop(const std::vector<int>& loop, const std::array<Face, 6>& faces, int type,
                     std::vector<std::array<int, 3>>& tris) {
    const int n = int(loop.size());
    if (n < 3) fail("loop shorter than 3", type);
    std::vector<Eigen::Vector3f> pos(n);
    for (int i = 0; i < n; ++i) pos[i] = edgeMid(loop[i]);
    Eigen::Vector3f loopNormal = Eigen::Vector3f::Zero();  // Newell normal
    for (int i = 0; i < n; ++i) loopNormal += pos[i].cross(pos[(i + 1) % n]);

    auto sameFace = [&](int a, int b) {
        for (const Face& f : faces)
            if (onFace(f, a) && onFace(f, b)) return true;
        return false;
    };
    constexpr float kForbidden = 1e12f;
    auto chordCost = [&](int i, int j) -> float {  // i < j
        if (j == i + 1 || (i == 0 && j == n - 1)) return 0.0f;  // a loop segment
        return sameFace(loop[i], loop[j]) ? kForbidden : 0.0f;
    };

    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> best(n * n, inf);
    std::vector<int> split(n * n, -1);
    for (int i = 0; i + 1 < n; ++i) best[i * n + i + 1] = 0.0f;
    for (int len = 2; len < n; ++len)
        for (int i = 0; i + len < n; ++i) {
            const int j = i + len;
            for (int k = i + 1; k < j; ++k) {
                const float c = best[i * n + k] + best[k * n + j] + chordCost(i, k) + chordCost(k, j) +
                                triangleCost(pos[i], pos[k], pos[j], loopNormal);
                if (c < best[i * n + j]) {
                    best[i * n + j] = c;
                    split[i * n + j] = k;
                }
            }
        }
    if (best[n - 1] >= kForbidden) fail("loop has no triangulation without face diagonals", type);

    std::vector<std::pair<int, int>> stack{{0, n - 1}};
    while (!stack.empty()) {
        auto [i, j] = stack.back();
        stack.pop_back();
        if (j - i < 2) continue;
        const int k = split[i * n + j];
        tris.push_back({loop[i], loop[k], loop[j]});
        stack.emplace_back(i, k);
        stack.emplace_back(k, j);
    }
}

MarchingCubesTables generate() {
    MarchingCubesTables t{};
    const auto faces = makeFaces();
    for (int type = 0; type < 256; ++type) {
        uint16_t mask = 0;
        for (int e = 0; e < kCubeEdges; ++e) {
            const auto c = edgeCorners(e);
            if (((type >> c[0]) & 1) != ((type >> c[1]) & 1)) mask |= uint16_t(1u << e);
        }
        t.edgeMask[type] = mask;

        std::vector<std::pair<int, int>> segs;
        for (const Face& f : faces) faceSegments(f, type, segs);
        int next[kCubeEdges], inDeg[kCubeEdges] = {};
        std::fill(std::begin(next), std::end(next), -1);
        for (auto [a, b] : segs) {
            if (next[a] != -1) fail("edge with two outgoing segments", type);
            next[a] = b;
            ++inDeg[b];
        }
        for (int e = 0; e < kCubeEdges; ++e) {
            const bool crossed = (mask >> e) & 1;
            if (crossed != (next[e] != -1) || inDeg[e] != (crossed ? 1 : 0)) fail("segments do not close", type);
        }

        // Chain the segments into loops, starting each loop at its lowest edge id (deterministic).
        std::vector<std::array<int, 3>> tris;
        bool visited[kCubeEdges] = {};
        for (int e = 0; e < kCubeEdges; ++e) {
            if (next[e] == -1 || visited[e]) continue;
            std::vector<int> loop;
            for (int x = e; !visited[x]; x = next[x]) {
                visited[x] = true;
                loop.push_back(x);
            }
            triangulateLoop(loop, faces, type, tris);
        }
        if (tris.size() > size_t(kMaxTrianglesPerCube)) fail("more than 5 triangles", type);
        t.triangleCount[type] = uint8_t(tris.size());
        for (int i = 0; i < 15; ++i) t.triangleEdges[type][i] = -1;
        for (size_t i = 0; i < tris.size(); ++i)
            for (int v = 0; v < 3; ++v) t.triangleEdges[type][i * 3 + v] = int8_t(tris[i][v]);
    }
    return t;
}

}  // namespace

const MarchingCubesTables& marchingCubesTables() {
    static const MarchingCubesTables tables = generate();
    return tables;
}

int maxTrianglesPerCube() {
    static const int m = [] {
        const auto& t = marchingCubesTables();
        return int(*std::max_element(std::begin(t.triangleCount), std::end(t.triangleCount)));
    }();
    return m;
}

}  // namespace vkmesh
