#include "io/ply.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace vkmesh {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
    throw Error("PLY file '" + path.string() + "': " + what);
}

// ---------------------------------------------------------------- writing

template <typename T>
void put(std::string& out, T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

void checkMesh(const std::filesystem::path& path, const Mesh& mesh, const char* kind) {
    auto bad = [&](const std::string& what) {
        throw Error(std::string(kind) + " file '" + path.string() + "': cannot write mesh: " + what);
    };
    const size_t n = mesh.positions.size();
    if (n > std::numeric_limits<uint32_t>::max()) bad("more than 2^32-1 vertices");
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        bad(std::to_string(mesh.normals.size()) + " normals for " + std::to_string(n) + " vertices");
    if (!mesh.vertexAge.empty() && mesh.vertexAge.size() != n)
        bad(std::to_string(mesh.vertexAge.size()) + " ages for " + std::to_string(n) + " vertices");
    if (!mesh.colors.empty() && mesh.colors.size() != n)
        bad(std::to_string(mesh.colors.size()) + " colours for " + std::to_string(n) + " vertices");
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        for (uint32_t v : mesh.triangles[i])
            if (v >= n)
                bad("triangle " + std::to_string(i) + " uses vertex " + std::to_string(v) + " of " +
                    std::to_string(n));
}

void writeFile(const std::filesystem::path& path, const std::string& data, const char* kind) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    if (!f) throw Error(std::string(kind) + " file '" + path.string() + "': cannot open for writing");
    f.write(data.data(), std::streamsize(data.size()));
    f.flush();
    if (!f) throw Error(std::string(kind) + " file '" + path.string() + "': write failed (disk full?)");
}

void appendNumber(std::string& out, float v) {
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.append(buf, r.ptr);
}
void appendNumber(std::string& out, uint64_t v) {
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.append(buf, r.ptr);
}

// ---------------------------------------------------------------- reading

// A value read from a file, for a message: integers without decimals.
std::string numberText(double v) {
    if (v == std::floor(v) && std::abs(v) < 1e18) return std::to_string(static_cast<long long>(v));
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof(buf), v);
    return std::string(buf, r.ptr);
}

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

std::optional<Scalar> scalarFromName(std::string_view s) {
    if (s == "char" || s == "int8") return Scalar::I8;
    if (s == "uchar" || s == "uint8") return Scalar::U8;
    if (s == "short" || s == "int16") return Scalar::I16;
    if (s == "ushort" || s == "uint16") return Scalar::U16;
    if (s == "int" || s == "int32") return Scalar::I32;
    if (s == "uint" || s == "uint32") return Scalar::U32;
    if (s == "float" || s == "float32") return Scalar::F32;
    if (s == "double" || s == "float64") return Scalar::F64;
    return std::nullopt;
}

size_t scalarSize(Scalar s) {
    switch (s) {
        case Scalar::I8: case Scalar::U8: return 1;
        case Scalar::I16: case Scalar::U16: return 2;
        case Scalar::I32: case Scalar::U32: case Scalar::F32: return 4;
        case Scalar::F64: return 8;
    }
    return 0;
}

bool isInteger(Scalar s) { return s != Scalar::F32 && s != Scalar::F64; }

const char* scalarName(Scalar s) {
    switch (s) {
        case Scalar::I8: return "char";
        case Scalar::U8: return "uchar";
        case Scalar::I16: return "short";
        case Scalar::U16: return "ushort";
        case Scalar::I32: return "int";
        case Scalar::U32: return "uint";
        case Scalar::F32: return "float";
        case Scalar::F64: return "double";
    }
    return "?";
}

// Whether an ascii value can be stored in the declared type: binary values always can, but an ascii file
// may hold "1e300" or "2.5" where the header promises a uchar list count, which must not reach a cast.
bool fitsScalar(Scalar s, double v) {
    if (!isInteger(s)) return true;  // float values: range handled where they are used
    if (!std::isfinite(v) || v != std::floor(v)) return false;
    switch (s) {
        case Scalar::I8: return v >= -128 && v <= 127;
        case Scalar::U8: return v >= 0 && v <= 255;
        case Scalar::I16: return v >= -32768 && v <= 32767;
        case Scalar::U16: return v >= 0 && v <= 65535;
        case Scalar::I32: return v >= -2147483648.0 && v <= 2147483647.0;
        case Scalar::U32: return v >= 0 && v <= 4294967295.0;
        default: return true;
    }
}

// double -> float without undefined behaviour: out-of-range values become +-infinity as in IEEE arithmetic.
float toFloat(double v) {
    if (v > double(std::numeric_limits<float>::max())) return std::numeric_limits<float>::infinity();
    if (v < -double(std::numeric_limits<float>::max())) return -std::numeric_limits<float>::infinity();
    return float(v);
}

// A colour channel as 0..255: integers as they are (ushort scaled down from 0..65535), floats as 0..1
// (Open3D's and PCL's convention for float colours); out-of-range values are clamped and NaN is 0, since a
// colour is not worth refusing a mesh for.
uint8_t colorByte(Scalar type, double v) {
    if (type == Scalar::U16) v /= 257.0;
    else if (!isInteger(type)) v *= 255.0;
    if (!(v > 0)) return 0;
    if (v >= 255) return 255;
    return uint8_t(std::lround(v));
}

enum class Role { Skip, X, Y, Z, NX, NY, NZ, Red, Green, Blue, Age, Indices };

struct Property {
    std::string name;
    Scalar type = Scalar::F32;  // scalar type, or the item type of a list
    bool isList = false;
    Scalar countType = Scalar::U8;
    Role role = Role::Skip;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> props;
};

enum class Format { Ascii, BinaryLE, BinaryBE };

std::vector<std::string_view> splitWords(std::string_view line) {
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        size_t j = i;
        while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
        if (j > i) words.push_back(line.substr(i, j - i));
        i = j;
    }
    return words;
}

// Reads the body values one at a time, as doubles (exact for every PLY integer type).
class BodyReader {
public:
    BodyReader(const std::filesystem::path& path, std::string_view body, Format format)
        : path_(path), body_(body), format_(format) {}

    // `what` says where we are, for the error message.
    double read(Scalar type, const char* what) {
        return format_ == Format::Ascii ? readAscii(type, what) : readBinary(type, what);
    }

private:
    template <typename T>
    T raw() {
        char b[sizeof(T)];
        std::memcpy(b, body_.data() + pos_, sizeof(T));
        if ((format_ == Format::BinaryBE) != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
        pos_ += sizeof(T);
        T v;
        std::memcpy(&v, b, sizeof(T));
        return v;
    }

    double readBinary(Scalar type, const char* what) {
        if (body_.size() - pos_ < scalarSize(type))
            fail(path_, std::string("truncated: the data ends inside ") + what + " (at byte " +
                            std::to_string(pos_) + " of " + std::to_string(body_.size()) + " body bytes)");
        switch (type) {
            case Scalar::I8: return raw<int8_t>();
            case Scalar::U8: return raw<uint8_t>();
            case Scalar::I16: return raw<int16_t>();
            case Scalar::U16: return raw<uint16_t>();
            case Scalar::I32: return raw<int32_t>();
            case Scalar::U32: return raw<uint32_t>();
            case Scalar::F32: return raw<float>();
            case Scalar::F64: return raw<double>();
        }
        return 0.0;
    }

    double readAscii(Scalar type, const char* what) {
        while (pos_ < body_.size() && std::isspace(static_cast<unsigned char>(body_[pos_]))) ++pos_;
        if (pos_ >= body_.size()) fail(path_, std::string("truncated: the data ends before ") + what);
        size_t end = pos_;
        while (end < body_.size() && !std::isspace(static_cast<unsigned char>(body_[end]))) ++end;
        std::string_view tok = body_.substr(pos_, end - pos_);
        pos_ = end;
        std::string_view num = tok;
        if (!num.empty() && num[0] == '+') num.remove_prefix(1);
        double v = 0.0;
        auto r = std::from_chars(num.data(), num.data() + num.size(), v);
        if (r.ec != std::errc() || r.ptr != num.data() + num.size())
            fail(path_, "corrupt: '" + std::string(tok) + "' is not a number (in " + what + ")");
        if (!fitsScalar(type, v))
            fail(path_, "corrupt: '" + std::string(tok) + "' is not a valid " + scalarName(type) + " (in " + what + ")");
        return v;
    }

    const std::filesystem::path& path_;
    std::string_view body_;
    Format format_;
    size_t pos_ = 0;
};

}  // namespace

void writePly(const std::filesystem::path& path, const Mesh& mesh) {
    checkMesh(path, mesh, "PLY");
    const bool hasNormals = !mesh.normals.empty();
    const bool hasAge = !mesh.vertexAge.empty();
    const bool hasColors = !mesh.colors.empty();
    std::string out;
    out += "ply\nformat binary_little_endian 1.0\ncomment written by vkmesh\n";
    out += "element vertex " + std::to_string(mesh.positions.size()) + "\n";
    out += "property float x\nproperty float y\nproperty float z\n";
    if (hasNormals) out += "property float nx\nproperty float ny\nproperty float nz\n";
    // uchar red/green/blue is the spelling Open3D, MeshLab and CloudCompare all read as vertex colour.
    if (hasColors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (hasAge) out += "property uint age\n";
    out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
    out += "property list uchar uint vertex_indices\nend_header\n";
    const size_t vertexBytes = 12 + (hasNormals ? 12 : 0) + (hasColors ? 3 : 0) + (hasAge ? 4 : 0);
    out.reserve(out.size() + mesh.positions.size() * vertexBytes + mesh.triangles.size() * 13);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) put<float>(out, mesh.positions[i][k]);
        if (hasNormals)
            for (int k = 0; k < 3; ++k) put<float>(out, mesh.normals[i][k]);
        if (hasColors)
            for (int k = 0; k < 3; ++k) put<uint8_t>(out, mesh.colors[i][k]);
        if (hasAge) put<uint32_t>(out, mesh.vertexAge[i]);
    }
    for (const auto& t : mesh.triangles) {
        put<uint8_t>(out, 3);
        for (uint32_t v : t) put<uint32_t>(out, v);
    }
    writeFile(path, out, "PLY");
}

void writeObj(const std::filesystem::path& path, const Mesh& mesh) {
    checkMesh(path, mesh, "OBJ");
    const bool hasNormals = !mesh.normals.empty();
    std::string out = "# written by vkmesh\n";
    out.reserve(mesh.positions.size() * (hasNormals ? 80 : 40) + mesh.triangles.size() * 40);
    auto vec = [&out](const char* tag, const Eigen::Vector3f& v) {
        out += tag;
        for (int k = 0; k < 3; ++k) {
            out += ' ';
            appendNumber(out, v[k]);
        }
        out += '\n';
    };
    // Colour as `v x y z r g b` with r, g, b in 0..1: not in the OBJ standard, but the extension MeshLab,
    // Open3D and Blender read.
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        if (mesh.colors.empty()) {
            vec("v", mesh.positions[i]);
            continue;
        }
        out += 'v';
        for (int k = 0; k < 3; ++k) {
            out += ' ';
            appendNumber(out, mesh.positions[i][k]);
        }
        for (int k = 0; k < 3; ++k) {
            out += ' ';
            appendNumber(out, float(mesh.colors[i][k]) / 255.0f);
        }
        out += '\n';
    }
    if (hasNormals)
        for (const auto& n : mesh.normals) vec("vn", n);
    for (const auto& t : mesh.triangles) {
        out += 'f';
        for (uint32_t v : t) {
            out += ' ';
            appendNumber(out, uint64_t(v) + 1);
            if (hasNormals) {
                out += "//";
                appendNumber(out, uint64_t(v) + 1);
            }
        }
        out += '\n';
    }
    writeFile(path, out, "OBJ");
}

Mesh readPly(const std::filesystem::path& path) {
    std::string data;
    {
        std::ifstream f(path, std::ios::binary);
        if (!f) fail(path, "cannot open for reading");
        data.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
        if (f.bad()) fail(path, "read error");
    }
    return parsePly(data, path);
}

Mesh parsePly(std::string_view data, const std::filesystem::path& path) {

    // --- header
    size_t pos = 0;
    auto nextLine = [&](std::string_view& line) {
        if (pos >= data.size()) return false;
        size_t nl = data.find('\n', pos);
        if (nl == std::string::npos) fail(path, "truncated header: it ends before the 'end_header' line");
        line = data.substr(pos, nl - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = nl + 1;
        return true;
    };
    std::string_view line;
    if (!nextLine(line) || line != "ply") fail(path, "not a PLY file (it does not start with 'ply')");
    std::optional<Format> format;
    std::vector<Element> elements;
    bool ended = false;
    while (!ended && nextLine(line)) {
        const auto w = splitWords(line);
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "format") {
            if (w.size() != 3) fail(path, "corrupt header line '" + std::string(line) + "'");
            if (w[1] == "ascii") format = Format::Ascii;
            else if (w[1] == "binary_little_endian") format = Format::BinaryLE;
            else if (w[1] == "binary_big_endian") format = Format::BinaryBE;
            else fail(path, "unsupported format '" + std::string(w[1]) + "'");
            if (w[2] != "1.0") fail(path, "unsupported PLY version '" + std::string(w[2]) + "'");
        } else if (w[0] == "element") {
            if (w.size() != 3) fail(path, "corrupt header line '" + std::string(line) + "'");
            Element e;
            e.name = std::string(w[1]);
            auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
            if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size())
                fail(path, "bad element count in '" + std::string(line) + "'");
            elements.push_back(std::move(e));
        } else if (w[0] == "property") {
            if (elements.empty()) fail(path, "property before any element: '" + std::string(line) + "'");
            Property p;
            if (w.size() == 5 && w[1] == "list") {
                auto ct = scalarFromName(w[2]), it = scalarFromName(w[3]);
                if (!ct || !it) fail(path, "unsupported property type in '" + std::string(line) + "'");
                if (!isInteger(*ct)) fail(path, "list count type must be an integer: '" + std::string(line) + "'");
                p.isList = true;
                p.countType = *ct;
                p.type = *it;
                p.name = std::string(w[4]);
            } else if (w.size() == 3) {
                auto t = scalarFromName(w[1]);
                if (!t) fail(path, "unsupported property type in '" + std::string(line) + "'");
                p.type = *t;
                p.name = std::string(w[2]);
            } else {
                fail(path, "corrupt header line '" + std::string(line) + "'");
            }
            elements.back().props.push_back(std::move(p));
        } else if (w[0] == "end_header") {
            ended = true;
        } else {
            fail(path, "unknown header keyword '" + std::string(w[0]) + "'");
        }
    }
    if (!ended) fail(path, "truncated header: it ends before the 'end_header' line");
    if (!format) fail(path, "header has no 'format' line");

    // --- roles
    const Element* vertexElem = nullptr;
    bool hasNx = false, hasNy = false, hasNz = false, hasAge = false;
    bool hasRed = false, hasGreen = false, hasBlue = false;
    bool hasX = false, hasY = false, hasZ = false;
    for (Element& e : elements) {
        if (e.name == "vertex") {
            if (vertexElem) fail(path, "two 'vertex' elements");
            vertexElem = &e;
            for (Property& p : e.props) {
                if (p.isList) continue;
                auto set = [&](Role r, bool& flag) {
                    if (flag) fail(path, "vertex property '" + p.name + "' declared twice");
                    flag = true;
                    p.role = r;
                };
                if (p.name == "x") set(Role::X, hasX);
                else if (p.name == "y") set(Role::Y, hasY);
                else if (p.name == "z") set(Role::Z, hasZ);
                else if (p.name == "nx") set(Role::NX, hasNx);
                else if (p.name == "ny") set(Role::NY, hasNy);
                else if (p.name == "nz") set(Role::NZ, hasNz);
                else if (p.name == "age") set(Role::Age, hasAge);
                // diffuse_* is the older spelling (some scanners, the Stanford repository's files).
                else if (p.name == "red" || p.name == "diffuse_red") set(Role::Red, hasRed);
                else if (p.name == "green" || p.name == "diffuse_green") set(Role::Green, hasGreen);
                else if (p.name == "blue" || p.name == "diffuse_blue") set(Role::Blue, hasBlue);
            }
        } else if (e.name == "face") {
            bool found = false;
            for (Property& p : e.props)
                if (p.isList && !found && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                    if (!isInteger(p.type)) fail(path, "face indices must be integers");
                    p.role = Role::Indices;
                    found = true;
                }
            if (!found && e.count > 0) fail(path, "face element without a 'vertex_indices' list");
        }
    }
    if (!vertexElem) fail(path, "no 'vertex' element");
    if (!(hasX && hasY && hasZ)) fail(path, "the vertex element lacks one of x, y, z");
    const bool keepNormals = hasNx && hasNy && hasNz;
    const bool keepColors = hasRed && hasGreen && hasBlue;

    // Sanity bound so a corrupt count cannot request absurd memory: each entry takes >= 1 byte (binary) or
    // >= 2 characters (ascii) per property.
    const size_t bodySize = data.size() - std::min(pos, data.size());
    for (const Element& e : elements)
        if (!e.props.empty() && e.count > bodySize)
            fail(path, "truncated: element '" + e.name + "' declares " + std::to_string(e.count) +
                           " entries but only " + std::to_string(bodySize) + " bytes of data follow the header");

    // --- body
    Mesh mesh;
    const size_t nv = size_t(vertexElem->count);
    mesh.positions.resize(nv, Eigen::Vector3f::Zero());
    if (keepNormals) mesh.normals.resize(nv, Eigen::Vector3f::Zero());
    if (hasAge) mesh.vertexAge.resize(nv, 0);
    if (keepColors) mesh.colors.resize(nv, {0, 0, 0});

    BodyReader in(path, data.substr(std::min(pos, data.size())), *format);
    std::vector<uint32_t> poly;
    for (const Element& e : elements) {
        // An element without properties has no data to read, whatever its count (up to 2^64-1 in a
        // corrupt header, which the loop below would otherwise spin through).
        if (e.props.empty()) continue;
        const bool isVertex = &e == vertexElem;
        const std::string whatEntry = "element '" + e.name + "'";
        for (uint64_t i = 0; i < e.count; ++i) {
            for (const Property& p : e.props) {
                if (p.isList) {
                    const double cnt = in.read(p.countType, whatEntry.c_str());
                    if (cnt < 0 || cnt != std::floor(cnt))
                        fail(path, "corrupt: negative list length in " + whatEntry + " entry " + std::to_string(i));
                    const size_t count = size_t(cnt);
                    if (p.role == Role::Indices) poly.clear();
                    for (size_t k = 0; k < count; ++k) {
                        const double v = in.read(p.type, whatEntry.c_str());
                        if (p.role == Role::Indices) {
                            if (v < 0 || v >= double(nv) || v != std::floor(v))
                                fail(path, "corrupt: face " + std::to_string(i) + " uses vertex " + numberText(v) +
                                               " of " + std::to_string(nv));
                            poly.push_back(uint32_t(v));
                        }
                    }
                    if (p.role == Role::Indices)
                        for (size_t k = 1; k + 1 < poly.size(); ++k)
                            mesh.triangles.push_back({poly[0], poly[k], poly[k + 1]});
                    continue;
                }
                const double v = in.read(p.type, whatEntry.c_str());
                if (!isVertex) continue;
                switch (p.role) {
                    case Role::X: case Role::Y: case Role::Z: {
                        // A vertex at infinity or NaN poisons every distance and bounding box computed from the
                        // mesh (eval, render); reject it rather than give silently wrong numbers.
                        const float f = toFloat(v);
                        if (!std::isfinite(f))
                            fail(path, "corrupt: vertex " + std::to_string(i) + " has coordinate " + p.name + " = " +
                                           numberText(v) + " (not a finite float)");
                        mesh.positions[i][p.role == Role::X ? 0 : p.role == Role::Y ? 1 : 2] = f;
                        break;
                    }
                    case Role::NX: if (keepNormals) mesh.normals[i].x() = toFloat(v); break;
                    case Role::NY: if (keepNormals) mesh.normals[i].y() = toFloat(v); break;
                    case Role::NZ: if (keepNormals) mesh.normals[i].z() = toFloat(v); break;
                    case Role::Red: case Role::Green: case Role::Blue:
                        if (keepColors)
                            mesh.colors[i][p.role == Role::Red ? 0 : p.role == Role::Green ? 1 : 2] = colorByte(p.type, v);
                        break;
                    case Role::Age:
                        if (v < 0 || v > double(std::numeric_limits<uint32_t>::max()))
                            fail(path, "corrupt: vertex " + std::to_string(i) + " has age " + numberText(v));
                        mesh.vertexAge[i] = uint32_t(v);
                        break;
                    default: break;
                }
            }
        }
    }
    return mesh;
}

}  // namespace vkmesh
