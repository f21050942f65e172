// The mesh-delta stream file (docs/DELTAS.md): a header, then one record per frame with that frame's
// vertex and triangle changes, little-endian, appended as frames are integrated, so that a remote viewer
// can follow the mesh (tail the file, or receive the same bytes over a socket).
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

#include "core/mesh_delta.h"

namespace vkmesh {

inline constexpr char kDeltaStreamMagic[8] = {'V', 'K', 'M', 'D', 'E', 'L', 'T', 'A'};
// Version 2: vertex records carry the vertex colour (36 bytes); version 1 streams (32-byte records, no colour)
// are rejected with a message saying so.
inline constexpr uint32_t kDeltaStreamVersion = 2;

class DeltaStreamWriter {
public:
    // Creates (truncates) the file; throws Error naming it when it cannot be written.
    explicit DeltaStreamWriter(const std::filesystem::path& path);
    ~DeltaStreamWriter();
    DeltaStreamWriter(const DeltaStreamWriter&) = delete;
    DeltaStreamWriter& operator=(const DeltaStreamWriter&) = delete;
    void write(const MeshDelta& delta);   // appends and flushes one frame
    uint64_t bytesWritten() const { return bytes_; }

private:
    void put(const void* data, size_t size);
    std::filesystem::path path_;
    std::FILE* file_ = nullptr;
    uint64_t bytes_ = 0;
};

// Reads every frame in order and hands it to `onFrame`. Throws Error naming the file (and the frame or
// byte offset) for a missing file, a wrong magic or version, or a truncated frame.
void readDeltaStream(const std::filesystem::path& path, const std::function<void(const MeshDelta&)>& onFrame);

}  // namespace vkmesh
