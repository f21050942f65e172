// Fuzz target: what the browser viewer's code reads from outside (src/viewer/wire.h). A page's text command
// (parseClientCommand: the only thing the server parses itself; HTTP and WebSocket framing are Boost.Beast's)
// and a binary viewer message (decodeMessage, used by tools and tests). A command that parses must hold what
// its grammar allows; a message that decodes must re-encode to the same bytes.
#include "fuzz_common.h"
#include "viewer/wire.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    vkmesh::viewer::ClientCommand command;
    if (vkmesh::viewer::parseClientCommand(bytes, command)) {
        if (bytes.size() > 4096) std::abort();
        for (const auto& [key, value] : command.report)
            if (key.empty() || key.size() > 64 || !std::isfinite(value)) std::abort();
    }
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        const vkmesh::viewer::DecodedMessage m = vkmesh::viewer::decodeMessage(bytes);
        const std::string again = vkmesh::viewer::encodeMessage(
            m.flags & ~vkmesh::viewer::kWireHasCamera, m.info, m.framesCoalesced, m.trajectory, m.delta.vertices.data(),
            m.delta.vertices.size(), m.delta.triangles.data(), m.delta.triangles.size());
        // hasCamera is the flag itself, so the flags survive; every other byte is copied as it was.
        if (again != bytes) std::abort();
    });
    return 0;
}
