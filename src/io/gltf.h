// Triangle meshes and point clouds as binary glTF 2.0 (.glb), the format Blender, Unity, three.js and web/AR
// viewers import. Written and read with tinygltf (Debian's libtinygltf-dev), never hand-written JSON.
#pragma once

#include "io/ply.h"   // Mesh

#include <filesystem>
#include <string_view>

namespace vkmesh {

// Writes `mesh` as binary glTF 2.0: one scene, one node, one mesh with one primitive (TRIANGLES, or POINTS for a
// point cloud: no triangles), one material (white, not metallic, rough, double-sided: fused surfaces are open and
// seen from both sides, and glTF's default material is fully metallic, which renders camera colours nearly black).
// Vertex attributes, each in a bufferView of its own:
//   POSITION  float VEC3 with min/max (the spec requires them);
//   NORMAL    float VEC3, when the mesh has normals: glTF requires unit normals, so each is normalised, and a zero or
//             non-finite one is replaced by its vertex's area-weighted face normal (by +Z for a vertex of no
//             triangle, or whose triangles are degenerate);
//   COLOR_0   when the mesh has colours: glTF vertex colours are linear, ours are sRGB camera colours, so they are
//             converted to linear (as three.js and Blender expect, which convert back for display) and stored as
//             normalised UNSIGNED_SHORT VEC4 (alpha 1): 16 bits keep every 8-bit sRGB value apart in linear space
//             (8-bit linear would merge the dark ones), so readGlb gives back the very same bytes;
//   _AGE      float SCALAR, when the mesh has ages (an application-specific attribute: glTF forbids unsigned int
//             attributes; exact up to 2^24 frames).
// Indices are UNSIGNED_INT (32 bit). An empty mesh (no vertices) is written as a valid glTF holding an empty scene.
// asset.generator is "vkmesh". Throws Error naming the file for an inconsistent mesh (attribute counts, an index
// out of range, a non-finite position) or a file that cannot be written.
void writeGlb(const std::filesystem::path& path, const Mesh& mesh);

// Reads a binary glTF 2.0 file: every primitive of every mesh whose mode is TRIANGLES (triangles) or POINTS (a point
// cloud), concatenated; node transforms are not applied (vkmesh's own files have none). POSITION must be float VEC3;
// NORMAL float VEC3; COLOR_0 normalised UNSIGNED_BYTE / UNSIGNED_SHORT or FLOAT, VEC3 or VEC4 (alpha ignored),
// converted from linear back to 8-bit sRGB; _AGE float SCALAR; indices UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT
// (or none: consecutive vertices). Normals, colours and ages are kept only when every primitive has them. Images
// are ignored, and buffers outside the file (external URIs) are refused, never looked up. Throws Error naming the
// file for a missing, truncated, corrupt or unsupported file (a sparse accessor, strips, fans or lines, quantised
// positions), never crashes.
Mesh readGlb(const std::filesystem::path& path);

// readGlb on the file's bytes already in memory; `path` only names the source in messages (fuzz target, tests).
Mesh parseGlb(std::string_view data, const std::filesystem::path& path);

}  // namespace vkmesh
