// Simplification of a mesh copy before it is written (`--simplify RATIO`): meshoptimizer's edge collapse
// (Debian's libmeshoptimizer-dev). Only the written copy is simplified; the live mesh on the GPU never is.
#pragma once

#include "io/ply.h"   // Mesh

#include <cstddef>
#include <string>

namespace vkmesh {

// What a simplification did: the ratio asked for, triangles before and after, and the geometric error meshoptimizer
// reports (its relative error times meshopt_simplifyScale, the mesh's extent: metres for vkmesh's meshes).
struct SimplifyReport {
    double ratio = 1;
    size_t trianglesBefore = 0, trianglesAfter = 0;
    double errorMetres = 0;
};

// The largest deviation simplification may cause, relative to the mesh's extent (1%: 5 cm on a 5 m room). The ratio
// is the goal; this bound only stops collapses that would visibly change the shape, so a mesh that cannot lose
// that many triangles within it keeps more than ratio * triangles (SimplifyReport says how many).
inline constexpr double kSimplifyMaxRelativeError = 0.01;

// Throws Error naming the value unless 0 < ratio <= 1 (`what` names where it came from, e.g. "--simplify").
void checkSimplifyRatio(double ratio, const std::string& what);

// A copy of `mesh` with about ratio * its triangles. Vertices at exactly the same position are welded first (the
// baseline mode's triangle soup has no shared vertices, and collapsing needs them; the first vertex's attributes are
// kept). Collapses only move vertices onto other vertices of the mesh, so every kept vertex keeps its own normal,
// colour and age; vertices no triangle uses any more are dropped. A point cloud (no triangles) is returned as it is.
// Throws Error for a bad ratio (checkSimplifyRatio) or an inconsistent mesh.
Mesh simplifyMesh(const Mesh& mesh, double ratio, SimplifyReport* report = nullptr);

}  // namespace vkmesh
