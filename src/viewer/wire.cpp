#include "viewer/wire.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <sstream>

#include "core/types.h"

namespace vkmesh::viewer {

namespace {

template <typename T>
void put(std::string& out, size_t& at, const T& value) {
    std::memcpy(out.data() + at, &value, sizeof(T));
    at += sizeof(T);
}

template <typename T>
T get(const std::string& in, size_t at) {
    T value;
    std::memcpy(&value, in.data() + at, sizeof(T));
    return value;
}

static_assert(sizeof(gpu::DeltaVertexRecord) == 36 && sizeof(gpu::DeltaTriangleRecord) == 16,
              "the page reads the records at these sizes (docs/VIEWER.md)");

}  // namespace

void RecordSet::clear() {
    vertices_.clear();
    triangles_.clear();
}

void RecordSet::apply(const MeshDelta& delta) {
    // Removals first, as a frame is applied (docs/DELTAS.md): an id removed and reused within the frame ends Added.
    for (const auto& r : delta.vertices)
        if (deltaKind(r.idKind) == DeltaKind::Removed) {
            if (keepRemovals_)
                vertices_[deltaId(r.idKind)] = r;
            else
                vertices_.erase(deltaId(r.idKind));
        }
    for (const auto& r : delta.triangles)
        if (deltaKind(r.idKind) == DeltaKind::Removed) {
            if (keepRemovals_)
                triangles_[deltaId(r.idKind)] = r;
            else
                triangles_.erase(deltaId(r.idKind));
        }
    // Added and Changed carry the whole vertex, so either one is the id's new content; kept as Added (a
    // Changed after an Added the page has not seen yet must still create the vertex there).
    for (auto r : delta.vertices)
        if (deltaKind(r.idKind) != DeltaKind::Removed) {
            r.idKind = deltaId(r.idKind) | (gpu::DELTA_ADDED << gpu::DELTA_KIND_SHIFT);
            vertices_[deltaId(r.idKind)] = r;
        }
    for (const auto& r : delta.triangles)
        if (deltaKind(r.idKind) != DeltaKind::Removed) triangles_[deltaId(r.idKind)] = r;
}

FrameInfo fusedFrameInfo(uint32_t frame, uint32_t totalFrames, double msPerFrame, uint32_t blocks, const Pose& cameraToWorld,
                         const Intrinsics& intrinsics) {
    FrameInfo info;
    info.frame = frame;
    info.totalFrames = totalFrames;
    info.msPerFrame = float(msPerFrame);
    info.blocks = blocks;
    info.hasCamera = true;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) info.cameraToWorld[4 * r + c] = float(cameraToWorld(r, c));
    info.intrinsics = {intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy};
    info.width = uint32_t(intrinsics.width), info.height = uint32_t(intrinsics.height);
    return info;
}

std::string encodeMessage(uint32_t flags, const FrameInfo& info, uint32_t framesCoalesced,
                          const std::vector<std::array<float, 3>>& trajectory, const gpu::DeltaVertexRecord* vertices,
                          size_t vertexCount, const gpu::DeltaTriangleRecord* triangles, size_t triangleCount) {
    std::string out(kWireHeaderBytes + trajectory.size() * 12 + vertexCount * sizeof(gpu::DeltaVertexRecord) +
                        triangleCount * sizeof(gpu::DeltaTriangleRecord),
                    '\0');
    size_t at = 0;
    put(out, at, kWireMagic);
    put(out, at, kWireVersion);
    put(out, at, flags | (info.hasCamera ? kWireHasCamera : 0u));
    put(out, at, info.frame);
    put(out, at, info.totalFrames);
    put(out, at, info.msPerFrame);
    put(out, at, info.blocks);
    put(out, at, uint32_t(trajectory.size()));
    put(out, at, uint32_t(vertexCount));
    put(out, at, uint32_t(triangleCount));
    for (float f : info.cameraToWorld) put(out, at, f);
    for (float f : info.intrinsics) put(out, at, f);
    put(out, at, info.width);
    put(out, at, info.height);
    put(out, at, framesCoalesced);
    put(out, at, info.source);
    for (const auto& p : trajectory)
        for (float f : p) put(out, at, f);
    if (vertexCount) std::memcpy(out.data() + at, vertices, vertexCount * sizeof(gpu::DeltaVertexRecord));
    at += vertexCount * sizeof(gpu::DeltaVertexRecord);
    if (triangleCount) std::memcpy(out.data() + at, triangles, triangleCount * sizeof(gpu::DeltaTriangleRecord));
    return out;
}

std::string encodeDelta(const MeshDelta& delta, const FrameInfo& info, const std::vector<std::array<float, 3>>& trajectory) {
    return encodeMessage(0, info, 1, trajectory, delta.vertices.data(), delta.vertices.size(), delta.triangles.data(),
                         delta.triangles.size());
}

std::string encodeRecordSet(const RecordSet& set, uint32_t flags, const FrameInfo& info, uint32_t framesCoalesced,
                            const std::vector<std::array<float, 3>>& trajectory) {
    std::vector<gpu::DeltaVertexRecord> vertices;
    std::vector<gpu::DeltaTriangleRecord> triangles;
    vertices.reserve(set.vertexCount());
    triangles.reserve(set.triangleCount());
    for (const auto& [id, r] : set.vertices()) vertices.push_back(r);
    for (const auto& [id, r] : set.triangles()) triangles.push_back(r);
    return encodeMessage(flags, info, framesCoalesced, trajectory, vertices.data(), vertices.size(), triangles.data(),
                         triangles.size());
}

std::string encodeMesh(const Mesh& mesh, const FrameInfo& info) {
    std::vector<gpu::DeltaVertexRecord> vertices(mesh.positions.size());
    for (size_t i = 0; i < vertices.size(); ++i) {
        gpu::DeltaVertexRecord& r = vertices[i];
        r.idKind = uint32_t(i);
        r.px = mesh.positions[i].x(), r.py = mesh.positions[i].y(), r.pz = mesh.positions[i].z();
        const Eigen::Vector3f n = mesh.normals.empty() ? Eigen::Vector3f::Zero() : mesh.normals[i];
        r.nx = n.x(), r.ny = n.y(), r.nz = n.z();
        r.createdFrame = 0;
        r.color = mesh.colors.empty() ? 0u
                                      : mesh.colors[i][0] | uint32_t(mesh.colors[i][1]) << 8 | uint32_t(mesh.colors[i][2]) << 16 |
                                            0xFFu << 24;
    }
    std::vector<gpu::DeltaTriangleRecord> triangles(mesh.triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i)
        triangles[i] = {uint32_t(i), mesh.triangles[i][0], mesh.triangles[i][1], mesh.triangles[i][2]};
    return encodeMessage(kWireReset, info, 0, {}, vertices.data(), vertices.size(), triangles.data(), triangles.size());
}

DecodedMessage decodeMessage(const std::string& bytes) {
    if (bytes.size() < kWireHeaderBytes)
        throw Error("viewer message of " + std::to_string(bytes.size()) + " bytes is shorter than its header (" +
                    std::to_string(kWireHeaderBytes) + ")");
    if (get<uint32_t>(bytes, 0) != kWireMagic) throw Error("viewer message has a wrong magic");
    if (get<uint32_t>(bytes, 4) != kWireVersion)
        throw Error("viewer message has version " + std::to_string(get<uint32_t>(bytes, 4)) + ", expected " +
                    std::to_string(kWireVersion));
    DecodedMessage m;
    m.flags = get<uint32_t>(bytes, 8);
    m.info.hasCamera = m.flags & kWireHasCamera;
    m.info.frame = get<uint32_t>(bytes, 12);
    m.info.totalFrames = get<uint32_t>(bytes, 16);
    m.info.msPerFrame = get<float>(bytes, 20);
    m.info.blocks = get<uint32_t>(bytes, 24);
    const uint64_t points = get<uint32_t>(bytes, 28), vertices = get<uint32_t>(bytes, 32), triangles = get<uint32_t>(bytes, 36);
    for (int i = 0; i < 12; ++i) m.info.cameraToWorld[i] = get<float>(bytes, 40 + 4 * i);
    for (int i = 0; i < 4; ++i) m.info.intrinsics[i] = get<float>(bytes, 88 + 4 * i);
    m.info.width = get<uint32_t>(bytes, 104);
    m.info.height = get<uint32_t>(bytes, 108);
    m.framesCoalesced = get<uint32_t>(bytes, 112);
    m.info.source = get<uint32_t>(bytes, 116);
    const uint64_t expected = kWireHeaderBytes + points * 12 + vertices * 36 + triangles * 16;
    if (expected != bytes.size())
        throw Error("viewer message of " + std::to_string(bytes.size()) + " bytes but its counts say " + std::to_string(expected));
    size_t at = kWireHeaderBytes;
    m.trajectory.resize(points);
    for (auto& p : m.trajectory)
        for (float& f : p) f = get<float>(bytes, at), at += 4;
    m.delta.frame = m.info.frame;
    m.delta.vertices.resize(vertices);
    if (vertices) std::memcpy(m.delta.vertices.data(), bytes.data() + at, vertices * 36);
    at += vertices * 36;
    m.delta.triangles.resize(triangles);
    if (triangles) std::memcpy(m.delta.triangles.data(), bytes.data() + at, triangles * 16);
    return m;
}

bool parseClientCommand(const std::string& text, ClientCommand& out) {
    if (text.size() > 4096) return false;
    auto number = [](std::string_view s, uint32_t& v) {
        if (s.empty()) return false;
        auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        return ec == std::errc() && end == s.data() + s.size();
    };
    std::string_view t(text);
    out = ClientCommand{};
    if (t == "play") return out.kind = ClientCommand::Kind::Play, true;
    if (t == "pause") return out.kind = ClientCommand::Kind::Pause, true;
    if (t.rfind("ack ", 0) == 0) return out.kind = ClientCommand::Kind::Ack, number(t.substr(4), out.value);
    if (t.rfind("seek ", 0) == 0) return out.kind = ClientCommand::Kind::Seek, number(t.substr(5), out.value);
    if (t.rfind("report", 0) == 0) {
        out.kind = ClientCommand::Kind::Report;
        std::istringstream in{std::string(t.substr(6))};
        std::string item;
        while (in >> item) {
            const size_t eq = item.find('=');
            if (eq == 0 || eq == std::string::npos || eq > 64) return false;
            for (size_t i = 0; i < eq; ++i)
                if (!(std::isalnum(static_cast<unsigned char>(item[i])) || item[i] == '_')) return false;
            double v = 0;
            const char* first = item.data() + eq + 1;
            auto [end, ec] = std::from_chars(first, item.data() + item.size(), v);
            if (ec != std::errc() || end != item.data() + item.size() || !std::isfinite(v)) return false;
            out.report.emplace_back(item.substr(0, eq), v);
        }
        return !out.report.empty();
    }
    return false;
}

}  // namespace vkmesh::viewer
