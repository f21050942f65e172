// Triangle meshes and point clouds on disk: PLY (read and write) and Wavefront OBJ (write).
#pragma once

#include "core/mesh.h"
#include "core/types.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

namespace vkmesh {

// Writes binary_little_endian 1.0 PLY: vertex `float x y z`, then `float nx ny nz` when normals are present,
// then `uchar red green blue` when colours are present, then `uint age` when ages are present; face `property list uchar uint vertex_indices` (always declared,
// possibly with 0 faces). Readable by Open3D and MeshLab. Throws Error when the mesh is inconsistent
// (normals/colours/ages count, index out of range) or the file cannot be written.
void writePly(const std::filesystem::path& path, const Mesh& mesh);

// Reads ascii, binary_little_endian or binary_big_endian PLY. Vertex x, y, z (any scalar type, float or
// double usually), optional nx, ny, nz, age and red, green, blue (or diffuse_red, ...: uchar as is, ushort
// scaled from 0..65535, float/double as 0..1; clamped); unknown properties and elements are skipped. Faces come from
// a `vertex_indices` (or `vertex_index`) list; polygons are split into triangle fans. A point cloud gives an
// empty `triangles`. Normals and colours are kept only when all three are present. Throws Error naming the file for a
// missing, corrupt, truncated or unsupported file.
Mesh readPly(const std::filesystem::path& path);

// readPly on the file's bytes already in memory; `path` only names the source in messages (for the fuzz
// target and tests).
Mesh parsePly(std::string_view data, const std::filesystem::path& path);

// Writes Wavefront OBJ: `v x y z` (`v x y z r g b`, r g b in 0..1, when colours are present: the de-facto
// extension MeshLab and Open3D read), `vn nx ny nz` when normals are present, `f a b c` (or `a//a ...`) with
// 1-based indices. Ages are not stored. Throws Error as writePly.
void writeObj(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace vkmesh
