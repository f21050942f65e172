// Fuzz target: the message decoders (io/recordings/messages.h). The first byte picks the decoder (its low 3
// bits) and the serialisation (bit 3: CDR, else ROS 1); the rest is the message. A decoded image must hold
// step * height bytes at least, as the decoder promises.
#include "fuzz_common.h"
#include "io/recordings/messages.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace vkmesh::io::recording;
    if (size == 0) return 0;
    const uint8_t pick = data[0];
    const std::span<const uint8_t> bytes(data + 1, size - 1);
    const Serialization s = (pick & 8) ? Serialization::Cdr : Serialization::Ros1;
    const std::string where = "fuzz.bag, message 0 on /fuzz";
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        switch (pick & 7) {
        case 0: {
            // The header from the leading bytes, as a dataset reads it (never throws), must be the whole message's.
            const auto head = decodeLeadingHeader(bytes.first(std::min<size_t>(bytes.size(), 64)), s);
            ImageMessage m = decodeImage(bytes, s, where);
            if (uint64_t(m.step) * m.height > m.data.size()) std::abort();
            if (head && (head->stampNs != m.header.stampNs || head->frameId != m.header.frameId)) std::abort();
            break;
        }
        case 1: decodeCameraInfo(bytes, s, where); break;
        case 2: decodeTfMessage(bytes, s, where); break;
        case 3: decodeTransform(bytes, s, where); break;
        case 4: decodeFloat32(bytes, s, where); break;
        case 5: decodeUInt32(bytes, s, where); break;
        case 6: decodeString(bytes, s, where); break;
        case 7: decodeKeyValue(bytes, s, where); break;
        }
    });
    return 0;
}
