// Fuzz target: the .vkmap reader (src/core/map_format.h, docs/MAPFILE.md; vkmesh fuse --load and vkmesh export
// read maps with it). Bad input must be a vkmesh::Error; a map it accepts must be one it can write back and
// read again to the same bytes, with every index the GPU would follow inside its pool.
#include "core/map_format.h"
#include "fuzz_common.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        using namespace vkmesh;
        const map::MapData m = map::parse(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.vkmap");
        const std::string again = map::serialize(m);
        const map::MapData n = map::parse(again, "rewritten.vkmap");   // must not throw
        if (map::serialize(n) != again) std::abort();
        const uint32_t vertices = m.vertexFree.firstUntouched;
        for (uint32_t w : m.chunkWords)
            if (w != gpu::INVALID_INDEX && w >= vertices) std::abort();
        for (const map::Block& b : m.blocks)
            if (b.index >= m.capacities.blocks) std::abort();
    });
    return 0;
}
