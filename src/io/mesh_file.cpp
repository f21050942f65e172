// Mesh files by extension (io/mesh_file.h).
#include "io/mesh_file.h"

#include "core/types.h"
#include "io/gltf.h"

#include <algorithm>
#include <cctype>
#include <string>

namespace vkmesh {

namespace {

std::string lowerExtension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

}  // namespace

MeshFormat meshFormatOf(const std::filesystem::path& path) {
    const std::string ext = lowerExtension(path);
    if (ext.empty() || ext == ".ply") return MeshFormat::Ply;
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".glb") return MeshFormat::Glb;
    throw Error("mesh file '" + path.string() + "': cannot write '" + path.extension().string() +
                "' files; the mesh formats are .ply (binary PLY), .obj (Wavefront OBJ) and .glb (binary glTF 2.0)");
}

void writeMesh(const std::filesystem::path& path, const Mesh& mesh) {
    switch (meshFormatOf(path)) {
        case MeshFormat::Ply: writePly(path, mesh); return;
        case MeshFormat::Obj: writeObj(path, mesh); return;
        case MeshFormat::Glb: writeGlb(path, mesh); return;
    }
}

Mesh readMesh(const std::filesystem::path& path) {
    return lowerExtension(path) == ".glb" ? readGlb(path) : readPly(path);
}

}  // namespace vkmesh
