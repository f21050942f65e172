// Fuzz target: the PLY reader (ascii, binary little and big endian; vkmesh eval and render read meshes
// with it). A mesh it returns must be consistent: every triangle index below the vertex count, normals and
// ages one per vertex or none, positions finite.
#include "fuzz_common.h"
#include "io/ply.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        vkmesh::Mesh m = vkmesh::parsePly(std::string_view(reinterpret_cast<const char*>(data), size), "mesh.ply");
        const size_t n = m.positions.size();
        if (!m.normals.empty() && m.normals.size() != n) std::abort();
        if (!m.vertexAge.empty() && m.vertexAge.size() != n) std::abort();
        for (const auto& p : m.positions)
            if (!p.allFinite()) std::abort();
        for (const auto& t : m.triangles)
            for (uint32_t v : t)
                if (v >= n) std::abort();
    });
    return 0;
}
