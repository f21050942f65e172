#include "io/delta_stream.h"

#include <bit>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

namespace vkmesh {

static_assert(std::endian::native == std::endian::little, "the stream is written in the host's (little-endian) order");

DeltaStreamWriter::DeltaStreamWriter(const std::filesystem::path& path) : path_(path) {
    file_ = std::fopen(path.string().c_str(), "wb");
    if (!file_) throw Error("cannot write the delta stream " + path.string() + ": " + std::strerror(errno));
    uint32_t header[2] = {kDeltaStreamVersion, 0};
    put(kDeltaStreamMagic, sizeof(kDeltaStreamMagic));
    put(header, sizeof(header));
    std::fflush(file_);
}

DeltaStreamWriter::~DeltaStreamWriter() {
    if (file_) std::fclose(file_);
}

void DeltaStreamWriter::put(const void* data, size_t size) {
    if (size && std::fwrite(data, 1, size, file_) != size)
        throw Error("cannot write the delta stream " + path_.string() + " (disk full?)");
    bytes_ += size;
}

void DeltaStreamWriter::write(const MeshDelta& delta) {
    uint32_t head[3] = {delta.frame, uint32_t(delta.vertices.size()), uint32_t(delta.triangles.size())};
    put(head, sizeof(head));
    put(delta.vertices.data(), delta.vertices.size() * sizeof(gpu::DeltaVertexRecord));
    put(delta.triangles.data(), delta.triangles.size() * sizeof(gpu::DeltaTriangleRecord));
    if (std::fflush(file_) != 0) throw Error("cannot write the delta stream " + path_.string());
}

void readDeltaStream(const std::filesystem::path& path, const std::function<void(const MeshDelta&)>& onFrame) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open the delta stream " + path.string());
    in.seekg(0, std::ios::end);
    const uint64_t size = uint64_t(in.tellg());
    in.seekg(0);
    char magic[8] = {};
    uint32_t header[2] = {};
    if (!in.read(magic, 8) || std::memcmp(magic, kDeltaStreamMagic, 8) != 0)
        throw Error(path.string() + " is not a vkmesh delta stream (no VKMDELTA magic)");
    if (!in.read(reinterpret_cast<char*>(header), sizeof(header)))
        throw Error(path.string() + ": truncated header");
    if (header[0] == 1)
        throw Error(path.string() + ": delta stream version 1 (written before vertex colours, 32-byte vertex records); this vkmesh "
                    "reads version " + std::to_string(kDeltaStreamVersion) + ": write the stream again with this vkmesh");
    if (header[0] != kDeltaStreamVersion)
        throw Error(path.string() + ": delta stream version " + std::to_string(header[0]) + ", this vkmesh reads version " +
                    std::to_string(kDeltaStreamVersion));
    uint64_t offset = 16;
    for (size_t index = 0; offset < size; ++index) {
        uint32_t head[3] = {};
        if (size - offset < sizeof(head) || !in.read(reinterpret_cast<char*>(head), sizeof(head)))
            throw Error(path.string() + ": frame record " + std::to_string(index) + " at byte " + std::to_string(offset) + " is truncated");
        offset += sizeof(head);
        const uint64_t need = uint64_t(head[1]) * sizeof(gpu::DeltaVertexRecord) + uint64_t(head[2]) * sizeof(gpu::DeltaTriangleRecord);
        if (need > size - offset)
            throw Error(path.string() + ": frame " + std::to_string(head[0]) + " (record " + std::to_string(index) + ") announces " +
                        std::to_string(head[1]) + " vertex and " + std::to_string(head[2]) + " triangle changes, " +
                        std::to_string(need) + " bytes, but only " + std::to_string(size - offset) + " remain: truncated");
        MeshDelta delta;
        delta.frame = head[0];
        delta.vertices.resize(head[1]);
        delta.triangles.resize(head[2]);
        in.read(reinterpret_cast<char*>(delta.vertices.data()), std::streamsize(head[1] * sizeof(gpu::DeltaVertexRecord)));
        in.read(reinterpret_cast<char*>(delta.triangles.data()), std::streamsize(head[2] * sizeof(gpu::DeltaTriangleRecord)));
        if (!in) throw Error(path.string() + ": cannot read frame " + std::to_string(head[0]));
        offset += need;
        onFrame(delta);
    }
}

}  // namespace vkmesh
