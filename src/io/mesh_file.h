// Mesh files by their extension: the one place that decides which writer (and reader) a path gets, used by every
// command that writes a mesh (fuse -o, export, correct, deltas) and by Python's Mesh.save.
#pragma once

#include "io/ply.h"   // Mesh

#include <filesystem>

namespace vkmesh {

enum class MeshFormat { Ply, Obj, Glb };

// The format a path names: .ply, .obj or .glb (any case); a path without an extension (e.g. /dev/null) is PLY, as it
// always was. Throws Error naming the path and listing the supported extensions for any other extension (.gltf,
// .stl, ...), so that a mistyped name fails before a long fusion rather than writing PLY under a wrong name.
MeshFormat meshFormatOf(const std::filesystem::path& path);

// Writes `mesh` in the format of meshFormatOf(path): writePly, writeObj or writeGlb. Throws Error as they do.
void writeMesh(const std::filesystem::path& path, const Mesh& mesh);

// Reads a mesh: readGlb for .glb (any case), readPly for anything else (the readers name the file in their errors).
Mesh readMesh(const std::filesystem::path& path);

}  // namespace vkmesh
