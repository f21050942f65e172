// Fuzz target: the binary glTF reader (vkmesh view and Python read_mesh read .glb files with it; tinygltf parses
// the JSON). A mesh it returns must be consistent: every triangle index below the vertex count, normals, colours
// and ages one per vertex or none, positions finite.
#include "fuzz_common.h"
#include "io/gltf.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        vkmesh::Mesh m = vkmesh::parseGlb(std::string_view(reinterpret_cast<const char*>(data), size), "mesh.glb");
        const size_t n = m.positions.size();
        if (!m.normals.empty() && m.normals.size() != n) std::abort();
        if (!m.colors.empty() && m.colors.size() != n) std::abort();
        if (!m.vertexAge.empty() && m.vertexAge.size() != n) std::abort();
        for (const auto& p : m.positions)
            if (!p.allFinite()) std::abort();
        for (const auto& t : m.triangles)
            for (uint32_t v : t)
                if (v >= n) std::abort();
    });
    return 0;
}
