// Marching-cubes conventions and tables, shared by the CPU reference and the GPU shaders.
//
// Conventions (the shaders rely on them, do not change):
//   * Corner i (0..7) of a cube sits at offset (i & 1, (i >> 1) & 1, (i >> 2) & 1) from the cube's origin.
//   * Bit i of a cube type is set when corner i's signed distance is < 0 (inside). >= 0 is free space.
//   * Edges are axis-major: 0-3 run along x, 4-7 along y, 8-11 along z. Edge 4 * axis + k starts at the
//     corner whose two other coordinates (in increasing axis order) are (k & 1, k >> 1) and whose own
//     coordinate is 0, and ends at the corner with that coordinate 1.
//   * A cube owns the three edges leaving its corner 0 (edges 0, 4, 8). Edge e of the cube at c is the
//     edge 4 * edgeAxis(e) of the cube at c + edgeOwnerOffset(e).
//   * Triangles are counter-clockwise seen from the positive side: with v0, v1, v2 on the edges listed,
//     (v1 - v0) x (v2 - v0) points toward positive signed distance.
//
// The tables are generated at first use (not copied from anywhere): on every cube face the crossing edges
// are joined into segments by a rule that depends only on that face's four corner signs (on an ambiguous
// face the two inside corners are kept apart), so two cubes sharing a face agree and the mesh is crack-free.
// The oriented segments are chained into closed loops over the cube surface and every loop is
// triangulated without diagonals lying on a cube face, preferring well-shaped triangles.
#pragma once

#include <array>
#include <cstdint>

namespace vkmesh {

inline constexpr int kCubeCorners = 8;
inline constexpr int kCubeEdges = 12;
inline constexpr int kMaxTrianglesPerCube = 5;  // upper bound guaranteed by the generated table

// Offset of corner c along `axis` (0 = x, 1 = y, 2 = z): 0 or 1.
constexpr int cornerCoord(int c, int axis) { return (c >> axis) & 1; }
constexpr std::array<int, 3> cornerOffset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }

// Axis an edge runs along: 0 = x, 1 = y, 2 = z.
constexpr int edgeAxis(int e) { return e >> 2; }

// The two corners of edge e: {low corner (edge's axis coordinate 0), high corner (1)}.
constexpr std::array<int, 2> edgeCorners(int e) {
    const int axis = e >> 2, k = e & 3;
    // The two other axes in increasing order get bits 0 and 1 of k.
    const int a0 = axis == 0 ? 1 : 0;
    const int a1 = axis == 2 ? 1 : 2;
    const int low = ((k & 1) << a0) | ((k >> 1) << a1);
    return {low, low | (1 << axis)};
}

// Offset of the cube that owns edge e (the offset of the edge's low corner); there it is edge 4 * edgeAxis(e).
constexpr std::array<int, 3> edgeOwnerOffset(int e) { return cornerOffset(edgeCorners(e)[0]); }

// The edge joining corners a and b (in either order), or -1 when they are not joined by a cube edge.
constexpr int edgeBetween(int a, int b) {
    for (int e = 0; e < kCubeEdges; ++e) {
        const auto c = edgeCorners(e);
        if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) return e;
    }
    return -1;
}

struct MarchingCubesTables {
    uint16_t edgeMask[256];         // bit e set when edge e has endpoints of different sign
    uint8_t triangleCount[256];     // 0..kMaxTrianglesPerCube
    int8_t triangleEdges[256][15];  // 3 edge ids per triangle, -1 padded
};

// The tables, generated once (thread-safe) on first call.
const MarchingCubesTables& marchingCubesTables();

// Largest triangleCount over all 256 types (5).
int maxTrianglesPerCube();

// Cube type from the 8 corner signed distances: bit i set iff d[i] < 0.
inline int cubeType(const float d[8]) {
    int t = 0;
    for (int i = 0; i < kCubeCorners; ++i)
        if (d[i] < 0.0f) t |= 1 << i;
    return t;
}

}  // namespace vkmesh
