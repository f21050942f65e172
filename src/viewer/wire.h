// The viewer's wire format (docs/VIEWER.md): what the server sends a page over its WebSocket, one binary
// message per update, built from the mesh-delta records (docs/DELTAS.md) so that a page applies exactly what
// `vkmesh deltas` applies. No Boost here: the encoding and the coalescing are tested without a socket.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/mesh_delta.h"
#include "io/ply.h"

namespace vkmesh::viewer {

inline constexpr uint32_t kWireMagic = 0x564D4B56u;   // "VKMV" little-endian
inline constexpr uint32_t kWireVersion = 1;
inline constexpr uint32_t kWireReset = 1u;            // flags: clear everything (mesh, trajectory) before applying
inline constexpr uint32_t kWireHasCamera = 2u;        // flags: pose and intrinsics are the current camera's
inline constexpr size_t kWireHeaderBytes = 120;
inline constexpr uint32_t kSourceMesh = 0, kSourceStream = 1, kSourceLive = 2;

// What a message says about the frame besides its records: shown by the page's overlay and frustum.
struct FrameInfo {
    uint32_t frame = 0;         // frames integrated so far (the last one this message includes); 0: none
    uint32_t totalFrames = 0;   // frames the run or file has (0: unknown)
    float msPerFrame = 0;       // fusion's wall time for that frame (0: not fused here)
    uint32_t blocks = 0;        // allocated blocks after it (0: unknown)
    bool hasCamera = false;
    std::array<float, 12> cameraToWorld{};   // rows of [R | t]
    std::array<float, 4> intrinsics{};       // fx, fy, cx, cy
    uint32_t width = 0, height = 0;
    uint32_t source = 0;        // kSourceMesh, kSourceStream or kSourceLive: what the page shows (player, "live")
};
// A fused frame's info (what `vkmesh fuse --serve` and Python's serve() publish): the camera at `cameraToWorld`
// with the depth image's intrinsics.
FrameInfo fusedFrameInfo(uint32_t frame, uint32_t totalFrames, double msPerFrame, uint32_t blocks, const Pose& cameraToWorld,
                         const Intrinsics& intrinsics);

// The mesh as the records that would build it: vertex and triangle records by id, every one Added. The server
// keeps one (what a page joining late receives first) and each slow page one (the changes it has not yet been
// sent, coalesced). apply() takes frames in order; a record replaces what its id held (last record wins), a
// removal deletes it: that is all a page needs, since it applies a message's records in any order.
class RecordSet {
public:
    void apply(const MeshDelta& delta);
    void clear();
    size_t vertexCount() const { return vertices_.size(); }
    size_t triangleCount() const { return triangles_.size(); }
    bool empty() const { return vertices_.empty() && triangles_.empty(); }
    // With `keepRemovals`, a removal is kept as a Removed record (pending changes for a page that has the id);
    // without, it deletes the id (the mesh itself).
    explicit RecordSet(bool keepRemovals) : keepRemovals_(keepRemovals) {}
    const std::unordered_map<uint32_t, gpu::DeltaVertexRecord>& vertices() const { return vertices_; }
    const std::unordered_map<uint32_t, gpu::DeltaTriangleRecord>& triangles() const { return triangles_; }

private:
    bool keepRemovals_;
    std::unordered_map<uint32_t, gpu::DeltaVertexRecord> vertices_;
    std::unordered_map<uint32_t, gpu::DeltaTriangleRecord> triangles_;
};

// One message: header, trajectory points (camera positions to append, x y z floats), vertex records (36 B),
// triangle records (16 B). `framesCoalesced`: how many frames it stands for (1 for a frame sent as it came).
std::string encodeMessage(uint32_t flags, const FrameInfo& info, uint32_t framesCoalesced,
                          const std::vector<std::array<float, 3>>& trajectory,
                          const gpu::DeltaVertexRecord* vertices, size_t vertexCount,
                          const gpu::DeltaTriangleRecord* triangles, size_t triangleCount);
std::string encodeDelta(const MeshDelta& delta, const FrameInfo& info, const std::vector<std::array<float, 3>>& trajectory);
std::string encodeRecordSet(const RecordSet& set, uint32_t flags, const FrameInfo& info, uint32_t framesCoalesced,
                            const std::vector<std::array<float, 3>>& trajectory);
// A host mesh as one Reset message: vertex id = index, triangle id = index (vertices without colour: alpha 0).
std::string encodeMesh(const Mesh& mesh, const FrameInfo& info);

// The decoded form, for tests and tools.
struct DecodedMessage {
    uint32_t flags = 0, framesCoalesced = 0;
    FrameInfo info;
    std::vector<std::array<float, 3>> trajectory;
    MeshDelta delta;   // delta.frame = info.frame
};
// Throws Error naming what is wrong (size, magic, version, counts that do not fit).
DecodedMessage decodeMessage(const std::string& bytes);

// Commands a page sends (text): "ack N" (applied the message up to frame N), "seek N" / "play" / "pause" (a
// stream file's slider), "report key=value ..." (measurements the page took, numbers only). Anything else is
// malformed and closes that page's connection.
struct ClientCommand {
    enum class Kind { Ack, Seek, Play, Pause, Report } kind = Kind::Ack;
    uint32_t value = 0;
    std::vector<std::pair<std::string, double>> report;
};
bool parseClientCommand(const std::string& text, ClientCommand& out);

}  // namespace vkmesh::viewer
