// Binary glTF 2.0 through tinygltf (io/gltf.h). This file holds tinygltf's implementation (it is header-only): no
// image codecs (vkmesh writes no textures and ignores those it reads), no file system access while reading (a
// buffer's external URI is refused rather than read from wherever a hostile file points).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <Eigen/Geometry>   // cross

#include "io/gltf.h"

#include "core/types.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace vkmesh {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
    throw Error("glTF file '" + path.string() + "': " + what);
}

// The sRGB transfer function (IEC 61966-2-1) both ways, on 0..1.
double srgbToLinear(double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); }
double linearToSrgb(double l) { return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055; }

// Every 8-bit sRGB value as 16-bit linear: the nearest 16-bit value of neighbouring sRGB values are at least
// ~20 apart (at the dark end, where the curve is flattest), so linearToSrgb brings each back to its own byte.
const std::array<uint16_t, 256>& srgbToLinear16() {
    static const std::array<uint16_t, 256> table = [] {
        std::array<uint16_t, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = uint16_t(std::lround(srgbToLinear(i / 255.0) * 65535.0));
        return t;
    }();
    return table;
}

uint8_t linearToSrgb8(double linear) {
    if (!(linear > 0)) return 0;   // also NaN
    if (linear >= 1) return 255;
    return uint8_t(std::lround(std::clamp(linearToSrgb(linear), 0.0, 1.0) * 255.0));
}

// ---------------------------------------------------------------- writing

void checkMesh(const std::filesystem::path& path, const Mesh& mesh) {
    auto bad = [&](const std::string& what) { fail(path, "cannot write mesh: " + what); };
    const size_t n = mesh.positions.size();
    if (n > std::numeric_limits<uint32_t>::max()) bad("more than 2^32-1 vertices");
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        bad(std::to_string(mesh.normals.size()) + " normals for " + std::to_string(n) + " vertices");
    if (!mesh.vertexAge.empty() && mesh.vertexAge.size() != n)
        bad(std::to_string(mesh.vertexAge.size()) + " ages for " + std::to_string(n) + " vertices");
    if (!mesh.colors.empty() && mesh.colors.size() != n)
        bad(std::to_string(mesh.colors.size()) + " colours for " + std::to_string(n) + " vertices");
    for (size_t i = 0; i < n; ++i)
        if (!mesh.positions[i].allFinite()) bad("vertex " + std::to_string(i) + " has a non-finite position");
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        for (uint32_t v : mesh.triangles[i])
            if (v >= n) bad("triangle " + std::to_string(i) + " uses vertex " + std::to_string(v) + " of " + std::to_string(n));
}

// Unit normals, as glTF requires: each normalised; a zero or non-finite one (a vertex of degenerate triangles only,
// or a caller's placeholder) is replaced by the area-weighted normal of its triangles, or +Z when that is zero too
// (no triangles: a point cloud's vertex). Replacing rather than refusing keeps a whole capture exportable because of
// a few bad vertices.
std::vector<Eigen::Vector3f> unitNormals(const Mesh& mesh) {
    std::vector<Eigen::Vector3f> normals(mesh.normals.size());
    std::vector<bool> bad(mesh.normals.size(), false);
    bool anyBad = false;
    for (size_t i = 0; i < normals.size(); ++i) {
        const Eigen::Vector3f& n = mesh.normals[i];
        const float length = n.norm();
        if (n.allFinite() && std::isfinite(length) && length > 0) {
            normals[i] = n / length;
        } else {
            bad[i] = anyBad = true;
            normals[i].setZero();
        }
    }
    if (!anyBad) return normals;
    for (const auto& t : mesh.triangles) {
        if (!bad[t[0]] && !bad[t[1]] && !bad[t[2]]) continue;
        const Eigen::Vector3f& a = mesh.positions[t[0]];
        const Eigen::Vector3f face = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);   // |face| = 2 area
        for (uint32_t v : t)
            if (bad[v]) normals[v] += face;
    }
    for (size_t i = 0; i < normals.size(); ++i) {
        if (!bad[i]) continue;
        const float length = normals[i].norm();
        normals[i] = std::isfinite(length) && length > 0 ? Eigen::Vector3f(normals[i] / length) : Eigen::Vector3f::UnitZ();
    }
    return normals;
}

// Appends `bytes` to the binary chunk as a bufferView of its own, 4-byte aligned (every glTF accessor must be
// aligned to its component size; 4 covers all used here). Returns the view's index.
int addView(tinygltf::Model& model, const void* data, size_t bytes, int target) {
    std::vector<unsigned char>& bin = model.buffers[0].data;
    bin.resize((bin.size() + 3) & ~size_t(3), 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bin.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), p, p + bytes);
    model.bufferViews.push_back(std::move(view));
    return int(model.bufferViews.size() - 1);
}

int addAccessor(tinygltf::Model& model, int view, int componentType, int type, size_t count, bool normalized = false) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = componentType;
    a.type = type;
    a.count = count;
    a.normalized = normalized;
    model.accessors.push_back(std::move(a));
    return int(model.accessors.size() - 1);
}

// ---------------------------------------------------------------- reading

// tinygltf's hooks, set so that reading never touches the disk or decodes an image: images are skipped (left
// empty), and a buffer with an external URI fails to load (its file "does not exist").
bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) { return true; }
bool noFile(const std::string&, void*) { return false; }
std::string samePath(const std::string& p, void*) { return p; }
bool noRead(std::vector<unsigned char>*, std::string* err, const std::string& p, void*) {
    if (err) *err += "external file '" + p + "' not read (only self-contained .glb files are)\n";
    return false;
}
bool noWrite(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }

uint32_t readLe32(std::string_view data, size_t at) {
    const auto* b = reinterpret_cast<const unsigned char*>(data.data() + at);
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

// The GLB container checked before tinygltf sees it (header, JSON chunk, optional BIN chunk, all inside the
// data), so that a truncated file gets a message that says so.
void checkContainer(std::string_view data, const std::filesystem::path& path) {
    if (data.size() < 20) fail(path, "truncated: " + std::to_string(data.size()) + " bytes, a GLB header and chunk need 20");
    if (data.substr(0, 4) != "glTF") fail(path, "not binary glTF (no 'glTF' magic; a .gltf JSON file is not read)");
    if (const uint32_t version = readLe32(data, 4); version != 2) fail(path, "GLB version " + std::to_string(version) + ", not 2");
    const uint32_t length = readLe32(data, 8);
    if (length < 20) fail(path, "the header says " + std::to_string(length) + " bytes, less than a GLB header and chunk (20)");
    if (length > data.size())
        fail(path, "truncated: the header says " + std::to_string(length) + " bytes, the file has " + std::to_string(data.size()));
    const uint32_t jsonLength = readLe32(data, 12);
    if (readLe32(data, 16) != 0x4E4F534Au) fail(path, "the first chunk is not JSON");
    if (jsonLength > length - 20) fail(path, "truncated: the JSON chunk runs past the end of the file");
    const size_t bin = 20 + size_t(jsonLength);
    if (length - bin >= 8) {
        const uint32_t binLength = readLe32(data, bin);
        if (binLength > length - bin - 8) fail(path, "truncated: the binary chunk runs past the end of the file");
    }
}

// One accessor's elements, bounds-checked against its bufferView and buffer.
struct AccessorData {
    const unsigned char* base = nullptr;
    size_t stride = 0, count = 0;
    int componentType = 0, components = 0;
    bool normalized = false;

    double component(size_t i, int c) const {
        const unsigned char* p = base + i * stride;
        auto get = [&](auto v) {
            std::memcpy(&v, p + c * sizeof(v), sizeof(v));
            return v;
        };
        switch (componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: return get(float{});
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? get(uint8_t{}) / 255.0 : get(uint8_t{});
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return normalized ? get(uint16_t{}) / 65535.0 : get(uint16_t{});
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return get(uint32_t{});
            case TINYGLTF_COMPONENT_TYPE_BYTE: return normalized ? std::max(get(int8_t{}) / 127.0, -1.0) : get(int8_t{});
            case TINYGLTF_COMPONENT_TYPE_SHORT: return normalized ? std::max(get(int16_t{}) / 32767.0, -1.0) : get(int16_t{});
            default: return 0;   // excluded by accessorData
        }
    }
};

AccessorData accessorData(const tinygltf::Model& model, int index, const std::string& what, const std::filesystem::path& path) {
    if (index < 0 || size_t(index) >= model.accessors.size()) fail(path, what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = model.accessors[index];
    const std::string name = what + " (accessor " + std::to_string(index) + ")";
    if (a.sparse.isSparse) fail(path, name + ": sparse accessors are not supported");
    if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size())
        fail(path, name + ": no bufferView (accessors without data are not supported)");
    const tinygltf::BufferView& v = model.bufferViews[a.bufferView];
    if (v.buffer < 0 || size_t(v.buffer) >= model.buffers.size()) fail(path, name + ": its bufferView names no buffer");
    const std::vector<unsigned char>& buffer = model.buffers[v.buffer].data;
    const int componentSize = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
    const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    if (componentSize <= 0 || components <= 0 || components > 4) fail(path, name + ": bad component type or element type");
    const size_t element = size_t(componentSize) * size_t(components);
    const size_t stride = v.byteStride ? v.byteStride : element;
    if (stride < element) fail(path, name + ": byteStride " + std::to_string(v.byteStride) + " is smaller than an element");
    if (v.byteOffset > buffer.size() || v.byteLength > buffer.size() - v.byteOffset)
        fail(path, name + ": its bufferView runs past the end of its buffer");
    AccessorData d;
    d.stride = stride;
    d.count = a.count;
    d.componentType = a.componentType;
    d.components = components;
    d.normalized = a.normalized;
    if (a.count == 0) return d;
    if (a.byteOffset > v.byteLength || element > v.byteLength - a.byteOffset ||
        a.count - 1 > (v.byteLength - a.byteOffset - element) / stride)
        fail(path, name + ": " + std::to_string(a.count) + " elements run past the end of its bufferView");
    d.base = buffer.data() + v.byteOffset + a.byteOffset;
    return d;
}

// Reads the attribute `semantic` of a primitive when present; checks its count against the primitive's vertices.
std::optional<AccessorData> attribute(const tinygltf::Model& model, const tinygltf::Primitive& p, const std::string& semantic,
                                      size_t vertices, const std::string& where, const std::filesystem::path& path) {
    auto it = p.attributes.find(semantic);
    if (it == p.attributes.end()) return std::nullopt;
    AccessorData d = accessorData(model, it->second, where + " " + semantic, path);
    if (d.count != vertices)
        fail(path, where + " " + semantic + ": " + std::to_string(d.count) + " elements for " + std::to_string(vertices) + " vertices");
    return d;
}

}  // namespace

void writeGlb(const std::filesystem::path& path, const Mesh& mesh) {
    checkMesh(path, mesh);
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "vkmesh";
    model.scenes.emplace_back();
    model.scenes[0].name = "vkmesh";   // tinygltf writes a scene with no property as null, which glTF forbids
    model.defaultScene = 0;
    const size_t n = mesh.positions.size();
    if (n > 0) {   // glTF has no empty accessor or primitive: an empty mesh is an empty scene
        model.buffers.emplace_back();
        model.buffers[0].data.reserve(n * (12 + 12 + 8 + 4) + mesh.triangles.size() * 12 + 16);   // no regrowth copies
        tinygltf::Primitive primitive;
        primitive.mode = mesh.triangles.empty() ? TINYGLTF_MODE_POINTS : TINYGLTF_MODE_TRIANGLES;

        const int positions = addAccessor(model, addView(model, mesh.positions.data(), n * 12, TINYGLTF_TARGET_ARRAY_BUFFER),
                                          TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
        Eigen::Vector3f lo = mesh.positions[0], hi = mesh.positions[0];
        for (const auto& p : mesh.positions) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
        model.accessors[positions].minValues = {lo.x(), lo.y(), lo.z()};
        model.accessors[positions].maxValues = {hi.x(), hi.y(), hi.z()};
        primitive.attributes["POSITION"] = positions;

        if (!mesh.normals.empty()) {
            const std::vector<Eigen::Vector3f> normals = unitNormals(mesh);
            primitive.attributes["NORMAL"] =
                addAccessor(model, addView(model, normals.data(), n * 12, TINYGLTF_TARGET_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_FLOAT,
                            TINYGLTF_TYPE_VEC3, n);
        }
        if (!mesh.colors.empty()) {
            const auto& toLinear = srgbToLinear16();
            std::vector<std::array<uint16_t, 4>> colors(n);
            for (size_t i = 0; i < n; ++i)
                colors[i] = {toLinear[mesh.colors[i][0]], toLinear[mesh.colors[i][1]], toLinear[mesh.colors[i][2]], 65535};
            primitive.attributes["COLOR_0"] =
                addAccessor(model, addView(model, colors.data(), n * 8, TINYGLTF_TARGET_ARRAY_BUFFER),
                            TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, n, /*normalized=*/true);
        }
        if (!mesh.vertexAge.empty()) {
            std::vector<float> ages(mesh.vertexAge.begin(), mesh.vertexAge.end());
            primitive.attributes["_AGE"] = addAccessor(model, addView(model, ages.data(), n * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
                                                       TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, n);
        }
        if (!mesh.triangles.empty())
            primitive.indices = addAccessor(
                model, addView(model, mesh.triangles.data(), mesh.triangles.size() * 12, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, mesh.triangles.size() * 3);

        tinygltf::Material material;
        material.name = "vkmesh";
        material.pbrMetallicRoughness.baseColorFactor = {1, 1, 1, 1};
        material.pbrMetallicRoughness.metallicFactor = 0;
        material.pbrMetallicRoughness.roughnessFactor = 1;
        material.doubleSided = true;
        model.materials.push_back(std::move(material));
        primitive.material = 0;

        tinygltf::Mesh gltfMesh;
        gltfMesh.name = "vkmesh";
        gltfMesh.primitives.push_back(std::move(primitive));
        model.meshes.push_back(std::move(gltfMesh));
        tinygltf::Node node;
        node.mesh = 0;
        model.nodes.push_back(std::move(node));
        model.scenes[0].nodes = {0};
    }
    // The vectors are copied into the binary chunk as they are: tightly packed, and glTF is little-endian.
    static_assert(sizeof(Eigen::Vector3f) == 12 && sizeof(std::array<uint32_t, 3>) == 12, "tightly packed vertex data");
    static_assert(std::endian::native == std::endian::little, "glTF's binary data is little-endian");

    // GLB sizes are 32-bit; the JSON chunk is a few KB.
    if (!model.buffers.empty() && model.buffers[0].data.size() > std::numeric_limits<uint32_t>::max() - (1u << 20))
        fail(path, "cannot write mesh: " + std::to_string(model.buffers[0].data.size()) + " bytes of vertex and index data, more than a GLB file can hold (4 GiB)");

    // Straight into the file: the binary chunk is most of it, and a string in between would copy it twice more.
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    if (!f) fail(path, "cannot open for writing");
    tinygltf::TinyGLTF gltf;
    if (!gltf.WriteGltfSceneToStream(&model, f, /*prettyPrint=*/false, /*writeBinary=*/true)) fail(path, "tinygltf could not serialise the mesh");
    f.flush();
    if (!f) fail(path, "write failed (disk full?)");
}

Mesh readGlb(const std::filesystem::path& path) {
    std::string data;
    {
        std::ifstream f(path, std::ios::binary);
        if (!f) fail(path, "cannot open for reading");
        data.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
        if (f.bad()) fail(path, "read error");
    }
    return parseGlb(data, path);
}

Mesh parseGlb(std::string_view data, const std::filesystem::path& path) {
    if (data.size() > std::numeric_limits<uint32_t>::max()) fail(path, "larger than 4 GiB, the most a GLB file can hold");
    checkContainer(data, path);
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(skipImage, nullptr);
    gltf.SetFsCallbacks({noFile, samePath, noRead, noWrite, nullptr});
    tinygltf::Model model;
    std::string err, warn;
    bool loaded = false;
    try {   // tinygltf reports through `err`; its JSON library may still throw on a hostile document
        loaded = gltf.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(data.data()), unsigned(data.size()));
    } catch (const std::exception& e) {
        err = e.what();
    }
    if (!loaded)
        fail(path, "not valid glTF: " + (err.empty() ? std::string("tinygltf gave no reason") : err.substr(0, err.find_last_not_of('\n') + 1)));

    Mesh mesh;
    bool allNormals = true, allColors = true, allAges = true;
    std::vector<Eigen::Vector3f> normals;
    std::vector<std::array<uint8_t, 3>> colors;
    std::vector<uint32_t> ages;
    for (size_t m = 0; m < model.meshes.size(); ++m) {
        for (size_t k = 0; k < model.meshes[m].primitives.size(); ++k) {
            const tinygltf::Primitive& p = model.meshes[m].primitives[k];
            const std::string where = "mesh " + std::to_string(m) + " primitive " + std::to_string(k);
            // tinygltf leaves an absent mode at -1; glTF's default is TRIANGLES.
            const bool triangles = p.mode == TINYGLTF_MODE_TRIANGLES || p.mode == -1;
            if (!triangles && p.mode != TINYGLTF_MODE_POINTS)
                fail(path, where + ": mode " + std::to_string(p.mode) + " (lines, strips or fans) is not supported");
            auto pos = p.attributes.find("POSITION");
            if (pos == p.attributes.end()) fail(path, where + ": no POSITION");
            const AccessorData positions = accessorData(model, pos->second, where + " POSITION", path);
            const tinygltf::Accessor& pa = model.accessors[pos->second];
            if (pa.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || pa.type != TINYGLTF_TYPE_VEC3)
                fail(path, where + " POSITION: not float VEC3 (quantised positions are not supported)");
            const size_t first = mesh.positions.size();
            const size_t n = positions.count;
            if (n > std::numeric_limits<uint32_t>::max() - first) fail(path, "more than 2^32-1 vertices");
            for (size_t i = 0; i < n; ++i) {
                Eigen::Vector3f v(float(positions.component(i, 0)), float(positions.component(i, 1)), float(positions.component(i, 2)));
                if (!v.allFinite()) fail(path, where + " POSITION " + std::to_string(i) + ": not finite");
                mesh.positions.push_back(v);
            }

            if (auto nd = attribute(model, p, "NORMAL", n, where, path)) {
                if (nd->componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || nd->components != 3)
                    fail(path, where + " NORMAL: not float VEC3 (quantised normals are not supported)");
                for (size_t i = 0; i < n; ++i)
                    normals.emplace_back(float(nd->component(i, 0)), float(nd->component(i, 1)), float(nd->component(i, 2)));
            } else {
                allNormals = false;
            }
            if (auto cd = attribute(model, p, "COLOR_0", n, where, path)) {
                const bool typeOk = cd->componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                    (cd->normalized && (cd->componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                                        cd->componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
                if (!typeOk || cd->components < 3)
                    fail(path, where + " COLOR_0: not VEC3/VEC4 of float or normalised unsigned byte/short");
                for (size_t i = 0; i < n; ++i)
                    colors.push_back({linearToSrgb8(cd->component(i, 0)), linearToSrgb8(cd->component(i, 1)), linearToSrgb8(cd->component(i, 2))});
            } else {
                allColors = false;
            }
            if (auto ad = attribute(model, p, "_AGE", n, where, path)) {
                if (ad->componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || ad->components != 1) fail(path, where + " _AGE: not float SCALAR");
                for (size_t i = 0; i < n; ++i) {
                    const double age = ad->component(i, 0);
                    ages.push_back(age > 0 ? uint32_t(std::min(std::round(age), 4294967295.0)) : 0u);   // NaN -> 0
                }
            } else {
                allAges = false;
            }

            if (!triangles) continue;   // a point cloud: its vertices are the points (indices, if any, add nothing)
            std::vector<uint32_t> indices;
            if (p.indices >= 0) {
                const AccessorData id = accessorData(model, p.indices, where + " indices", path);
                if (id.components != 1 || (id.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                           id.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                           id.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                    fail(path, where + " indices: not unsigned byte, short or int scalars");
                indices.reserve(id.count);
                for (size_t i = 0; i < id.count; ++i) {
                    const double v = id.component(i, 0);   // integer component types: the index itself
                    if (v >= double(n)) fail(path, where + " index " + std::to_string(i) + " is " + std::to_string(uint64_t(v)) + ", past " + std::to_string(n) + " vertices");
                    indices.push_back(uint32_t(v));
                }
            } else {
                indices.resize(n);
                for (size_t i = 0; i < n; ++i) indices[i] = uint32_t(i);
            }
            if (indices.size() % 3) fail(path, where + ": " + std::to_string(indices.size()) + " indices, not a multiple of 3");
            for (size_t i = 0; i < indices.size(); i += 3)
                mesh.triangles.push_back({uint32_t(first + indices[i]), uint32_t(first + indices[i + 1]), uint32_t(first + indices[i + 2])});
        }
    }
    if (allNormals) mesh.normals = std::move(normals);
    if (allColors) mesh.colors = std::move(colors);
    if (allAges) mesh.vertexAge = std::move(ages);
    return mesh;
}

}  // namespace vkmesh
