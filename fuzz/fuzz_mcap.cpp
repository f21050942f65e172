// Fuzz target: the MCAP reader (io/recordings/mcap.cpp) on bytes in memory, then every message it
// indexed read back (chunks decompressed again, zstd and lz4, CRC-32 checked). What it returns must be consistent: every message
// on a listed connection, sorted by time, the per-connection counts adding up.
#include "fuzz_common.h"
#include "io/recordings/container.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace vkmesh::io::recording;
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        auto c = openMcap(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.mcap");
        uint64_t total = 0, last = 0;
        for (const auto& k : c->connections()) total += k.messageCount;
        if (total != c->messages().size()) std::abort();
        for (const auto& m : c->messages()) {
            if (m.connection >= c->connections().size() || m.logTimeNs < last) std::abort();
            last = m.logTimeNs;
            vkmesh::fuzz::expectOnlyVkmeshErrors([&] { c->read(m); });
        }
    });
    return 0;
}
