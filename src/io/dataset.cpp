#include "io/dataset.h"
#include "io/data_dir.h"
#include "io/parsers.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

namespace vkmesh {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------------
// Small text helpers

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string fmt(double v) {
    std::ostringstream os;
    os.precision(10);
    os << v;
    return os.str();
}

std::string fmtFixed(double v, int decimals) {
    std::ostringstream os;
    os << std::fixed;
    os.precision(decimals);
    os << v;
    return os.str();
}

// Timestamps as written in the files: Unix seconds keep their microseconds, frame indices stay integers.
std::string fmtTime(double t) {
    if (t == std::floor(t) && std::abs(t) < 1e15) return std::to_string(static_cast<long long>(t));
    std::string s = fmtFixed(t, 6);
    while (s.back() == '0') s.pop_back();
    return s;
}

// "file:line" for messages; the whole path so that the user can open it straight away.
std::string at(const fs::path& file, size_t line) { return file.string() + ":" + std::to_string(line); }
std::string at(const std::string& source, size_t line) { return source + ":" + std::to_string(line); }

std::vector<std::string> splitWhitespace(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream is(line);
    for (std::string tok; is >> tok;) out.push_back(tok);
    return out;
}

// Locale-independent number parsing (strtod would read "1,5" in a German locale); the whole token must
// be a number, so "1.2abc" is rejected rather than silently read as 1.2.
bool parseNumber(std::string_view tok, double& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);  // from_chars refuses a leading '+'
    if (tok.empty()) return false;
    auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return ec == std::errc() && end == tok.data() + tok.size();
}

bool parseInteger(std::string_view tok, long long& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return ec == std::errc() && end == tok.data() + tok.size();
}

std::string joined(const std::vector<std::string>& tokens) {
    std::string s;
    for (const auto& t : tokens) s += (s.empty() ? "" : " ") + t;
    return s;
}

struct TextLine {
    size_t number;                    // 1-based, as an editor shows it
    std::vector<std::string> tokens;  // whitespace-separated
};

// The non-blank, non-comment lines of a text file. Blank lines (a trailing newline, CRLF endings) are
// harmless and skipped; '#' starts a comment line as in the TUM files.
std::vector<TextLine> readDataLines(std::istream& in, const std::string& source) {
    std::vector<TextLine> out;
    std::string line;
    for (size_t n = 1; std::getline(in, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        out.push_back({n, splitWhitespace(line)});
    }
    if (in.bad()) throw Error("error while reading " + source);
    return out;
}

std::ifstream openText(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw Error("cannot open " + file.string());
    return in;
}

// True if `word` occurs in `name` not preceded by a letter and not followed by a digit: "tum_fr1_rpy" and
// "rgbd_dataset_freiburg1_rpy" name freiburg 1, "iclnuim_office" names ICL-NUIM, but "bicycle" does not.
bool containsWord(const std::string& name, const std::string& word) {
    for (size_t pos = name.find(word); pos != std::string::npos; pos = name.find(word, pos + 1)) {
        bool leftOk = pos == 0 || !std::isalpha(static_cast<unsigned char>(name[pos - 1]));
        size_t end = pos + word.size();
        bool rightOk = end == name.size() || !std::isdigit(static_cast<unsigned char>(name[end]));
        if (leftOk && rightOk) return true;
    }
    return false;
}

// Orders file names as a person would ("2.png" before "10.png"); identical to plain name order for the
// zero-padded names Redwood ships, and right for the unpadded ones some converters write.
bool naturalLess(const std::string& a, const std::string& b) {
    size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        bool da = std::isdigit(static_cast<unsigned char>(a[i])), db = std::isdigit(static_cast<unsigned char>(b[j]));
        if (da && db) {
            size_t i2 = i, j2 = j;
            while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
            while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
            std::string_view na(a.data() + i, i2 - i), nb(b.data() + j, j2 - j);
            while (na.size() > 1 && na.front() == '0') na.remove_prefix(1);
            while (nb.size() > 1 && nb.front() == '0') nb.remove_prefix(1);
            if (na.size() != nb.size()) return na.size() < nb.size();
            if (na != nb) return na < nb;
            i = i2;
            j = j2;
        } else {
            if (a[i] != b[j]) return a[i] < b[j];
            ++i;
            ++j;
        }
    }
    return (a.size() - i) < (b.size() - j) || ((a.size() - i) == (b.size() - j) && a < b);
}

// ---------------------------------------------------------------------------------------------------
// Depth images

std::string describeType(const cv::Mat& m) {
    static const char* depthNames[] = {"8-bit unsigned", "8-bit signed", "16-bit unsigned", "16-bit signed",
                                       "32-bit signed",  "32-bit float", "64-bit float",    "16-bit float"};
    int d = m.depth();
    std::string s = (d >= 0 && d < 8) ? depthNames[d] : "unknown depth " + std::to_string(d);
    int c = m.channels();
    return s + ", " + std::to_string(c) + (c == 1 ? " channel" : " channels");
}

// Reads a depth PNG as raw uint16 samples. Everything that can go wrong is reported with the file's name.
cv::Mat readRawDepth(const fs::path& file) {
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) throw Error("depth image " + file.string() + " does not exist");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error("cannot open depth image " + file.string());
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error("error while reading depth image " + file.string());
    return io::decodeDepthPng(bytes, file.string());
}

// ---------------------------------------------------------------------------------------------------
// Poses

Pose poseFromQuaternion(double tx, double ty, double tz, double qx, double qy, double qz, double qw,
                        const std::string& where) {
    Eigen::Quaterniond q(qw, qx, qy, qz);
    double n = q.norm();
    // Files round the quaternion to 4-6 digits, so it is only approximately unit; a norm far from 1 means
    // the line is corrupt (swapped columns, a zeroed field), not a rounding issue.
    if (!std::isfinite(n) || n < 0.5 || n > 2.0)
        throw Error(where + ": quaternion (" + fmt(qx) + " " + fmt(qy) + " " + fmt(qz) + " " + fmt(qw) +
                    ") has norm " + fmt(n) + "; expected about 1");
    q.normalize();
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = q.toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(tx, ty, tz);
    return T;
}

}  // namespace

// =====================================================================================================
// The parsers on text and bytes (io/parsers.h); the layout readers below open the files and call these.

namespace io {

std::vector<TimedPose> parseTrajectory(std::istream& in, const std::string& source) {
    std::vector<TimedPose> out;
    for (const auto& l : readDataLines(in, source)) {
        if (l.tokens.size() != 8)
            throw Error(at(source, l.number) + ": expected 8 values 'timestamp tx ty tz qx qy qz qw', got " +
                        std::to_string(l.tokens.size()));
        double v[8];
        for (int k = 0; k < 8; ++k) {
            if (!parseNumber(l.tokens[k], v[k]))
                throw Error(at(source, l.number) + ": '" + l.tokens[k] + "' is not a number");
            if (!std::isfinite(v[k]))
                throw Error(at(source, l.number) + ": value '" + l.tokens[k] + "' is not finite");
        }
        std::string where = at(source, l.number);
        Pose T = poseFromQuaternion(v[1], v[2], v[3], v[4], v[5], v[6], v[7], where);
        validatePose(T, where);
        out.push_back({v[0], l.number, T});
    }
    return out;
}

std::vector<TimedPath> parseDepthList(std::istream& in, const std::string& source, const fs::path& folder) {
    std::vector<TimedPath> out;
    for (const auto& l : readDataLines(in, source)) {
        double t;
        if (l.tokens.size() != 2 || !parseNumber(l.tokens[0], t))
            throw Error(at(source, l.number) + ": expected 'timestamp path', got '" + joined(l.tokens) + "'");
        if (!std::isfinite(t)) throw Error(at(source, l.number) + ": timestamp " + l.tokens[0] + " is not finite");
        out.push_back({t, l.number, folder / l.tokens[1]});
    }
    return out;
}

// Pairs "timestamp path" side by side, in either order (TUM's associate.py writes rgb first, ICL-NUIM
// depth first); the depth pair is the one whose path mentions "depth".
std::vector<TimedPath> parseAssociations(std::istream& in, const std::string& source, const fs::path& folder) {
    std::vector<TimedPath> out;
    for (const auto& l : readDataLines(in, source)) {
        bool found = false;
        for (size_t i = 0; i + 1 < l.tokens.size(); ++i) {
            double t;
            if (parseNumber(l.tokens[i], t) && lower(l.tokens[i + 1]).find("depth") != std::string::npos) {
                if (!std::isfinite(t)) throw Error(at(source, l.number) + ": timestamp " + l.tokens[i] + " is not finite");
                out.push_back({t, l.number, folder / l.tokens[i + 1]});
                found = true;
                break;
            }
        }
        if (!found) throw Error(at(source, l.number) + ": no 'timestamp depth/...png' pair on this line");
    }
    return out;
}

// Blocks of five lines: "id id frame" then the camera-to-world matrix, one row per line.
std::vector<IndexedPose> parseRedwoodLog(std::istream& in, const std::string& source) {
    std::vector<TextLine> lines = readDataLines(in, source);
    std::vector<IndexedPose> out;
    for (size_t i = 0; i < lines.size(); i += 5) {
        const TextLine& h = lines[i];
        long long ids[3];
        if (h.tokens.size() != 3 || !parseInteger(h.tokens[0], ids[0]) || !parseInteger(h.tokens[1], ids[1]) ||
            !parseInteger(h.tokens[2], ids[2]))
            throw Error(at(source, h.number) + ": expected a block header of 3 integers 'id id frame', got '" +
                        joined(h.tokens) + "'");
        if (i + 5 > lines.size())
            throw Error(at(source, h.number) + ": the file ends inside the 4x4 matrix of frame " + std::to_string(ids[0]));
        Pose T;
        for (int r = 0; r < 4; ++r) {
            const TextLine& l = lines[i + 1 + r];
            if (l.tokens.size() != 4)
                throw Error(at(source, l.number) + ": expected 4 numbers (row " + std::to_string(r + 1) +
                            " of a 4x4 matrix), got " + std::to_string(l.tokens.size()));
            for (int c = 0; c < 4; ++c)
                if (!parseNumber(l.tokens[c], T(r, c)))
                    throw Error(at(source, l.number) + ": '" + l.tokens[c] + "' is not a number");
        }
        validatePose(T, at(source, lines[i + 1].number) + " (frame " + std::to_string(ids[0]) + ")");
        out.push_back({ids[0], h.number, T});
    }
    return out;
}

std::vector<double> parseNumbers(std::istream& in, const std::string& source, size_t count, const std::string& what) {
    std::vector<double> out;
    for (const auto& l : readDataLines(in, source))
        for (const auto& tok : l.tokens) {
            double v;
            if (!parseNumber(tok, v)) throw Error(at(source, l.number) + ": '" + tok + "' is not a number");
            if (out.size() == count)
                throw Error(at(source, l.number) + ": more than " + std::to_string(count) + " numbers; expected " +
                            std::to_string(count) + " (" + what + ")");
            out.push_back(v);
        }
    if (out.size() != count)
        throw Error(source + ": found " + std::to_string(out.size()) + " numbers; expected " + std::to_string(count) +
                    " (" + what + ")");
    return out;
}

CameraJson parseCameraJson(std::istream& in, const std::string& source) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw Error(source + ": not valid JSON: " + e.what());
    }
    if (!j.is_object()) throw Error(source + ": expected a JSON object with fx, fy, cx, cy, depth_scale");
    // A value quoted in a message: short, and never throwing on odd content.
    auto quote = [](const nlohmann::json& v) {
        std::string s = v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        return s.size() > 60 ? s.substr(0, 57) + "..." : s;
    };
    auto get = [&](const char* key) -> std::optional<double> {
        auto it = j.find(key);
        if (it == j.end()) return std::nullopt;
        if (!it->is_number()) throw Error(source + ": \"" + key + "\" is " + quote(*it) + "; expected a number");
        double v = it->get<double>();
        if (!std::isfinite(v)) throw Error(source + ": \"" + key + "\" = " + fmt(v) + " is not finite");
        return v;
    };
    auto getSize = [&](const char* key) -> std::optional<int> {
        auto it = j.find(key);
        if (it == j.end()) return std::nullopt;
        // Compared as doubles first: a huge or negative integer must not wrap when converted.
        if (!it->is_number_integer() || it->get<double>() < 1 || it->get<double>() > kMaxDepthImageSide)
            throw Error(source + ": \"" + key + "\" is " + quote(*it) + "; expected an image size in pixels (1.." +
                        std::to_string(kMaxDepthImageSide) + ")");
        return static_cast<int>(it->get<long long>());
    };
    CameraJson c;
    c.fx = get("fx");
    c.fy = get("fy");
    c.cx = get("cx");
    c.cy = get("cy");
    c.depthScale = get("depth_scale");
    c.width = getSize("width");
    c.height = getSize("height");
    c.colorFx = get("color_fx");
    c.colorFy = get("color_fy");
    c.colorCx = get("color_cx");
    c.colorCy = get("color_cy");
    c.colorWidth = getSize("color_width");
    c.colorHeight = getSize("color_height");
    static const char* known[] = {"fx",       "fy",       "cx",       "cy",          "depth_scale",  "width", "height",
                                  "color_fx", "color_fy", "color_cx", "color_cy", "color_width", "color_height"};
    for (const auto& item : j.items())
        if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return item.key() == k; }) ==
            std::end(known))
            c.ignoredKeys.push_back(quote(item.key()));
    // A file with none of the keys (another tool's format, e.g. Open3D's "intrinsic_matrix", or every key
    // misspelt) would otherwise be ignored in silence and the layout's default calibration used.
    const bool anyColor = c.colorFx || c.colorFy || c.colorCx || c.colorCy || c.colorWidth || c.colorHeight;
    if (!c.fx && !c.fy && !c.cx && !c.cy && !c.depthScale && !c.width && !c.height && !anyColor) {
        std::string found;
        for (const auto& k : c.ignoredKeys) found += (found.empty() ? "" : ", ") + k;
        throw Error(source + ": holds none of the keys fx, fy, cx, cy, depth_scale, width, height" +
                    (found.empty() ? std::string(" (it is empty)") : " (found " + found + ")"));
    }
    if ((c.fx && *c.fx == 0) || (c.fy && *c.fy == 0))
        throw Error(source + ": focal length " + std::string(c.fx && *c.fx == 0 ? "\"fx\"" : "\"fy\"") +
                    " = 0; it must be non-zero");
    // A negative fx mirrors the image left-right; no supported layout uses one. (A negative fy is ICL-NUIM's
    // convention, checked against the layout in Dataset::open.)
    if (c.fx && *c.fx < 0) throw Error(source + ": focal length \"fx\" = " + fmt(*c.fx) + " is negative; it must be positive");
    if (c.depthScale && *c.depthScale <= 0)
        throw Error(source + ": \"depth_scale\" = " + fmt(*c.depthScale) + "; it must be positive");
    // Half a colour calibration cannot be completed from the depth camera's without guessing.
    const bool allColor = c.colorFx && c.colorFy && c.colorCx && c.colorCy;
    if ((c.colorFx || c.colorFy || c.colorCx || c.colorCy) && !allColor)
        throw Error(source + ": colour intrinsics need all four of color_fx, color_fy, color_cx, color_cy");
    if ((c.colorWidth || c.colorHeight) && !allColor)
        throw Error(source + ": color_width/color_height given without color_fx, color_fy, color_cx, color_cy");
    if (c.colorFx && !(*c.colorFx > 0)) throw Error(source + ": \"color_fx\" = " + fmt(*c.colorFx) + "; it must be positive");
    if (c.colorFy && *c.colorFy == 0) throw Error(source + ": \"color_fy\" = 0; it must be non-zero");
    return c;
}

namespace {

std::string describePng(int bitDepth, int colorType) {
    std::string kind;
    switch (colorType) {
        case 0: kind = "grayscale, 1 channel"; break;
        case 2: kind = "RGB, 3 channels"; break;
        case 3: kind = "palette colour, 3 channels"; break;
        case 4: kind = "grayscale + alpha, 2 channels"; break;
        case 6: kind = "RGBA, 4 channels"; break;
        default: kind = "unknown colour type " + std::to_string(colorType); break;
    }
    return std::to_string(bitDepth) + "-bit " + kind;
}

}  // namespace

cv::Mat decodeDepthPng(std::string_view bytes, const std::string& source) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() < 8 || std::memcmp(bytes.data(), signature, 8) != 0)
        throw Error("depth image " + source + " is not a PNG file" +
                    (bytes.empty() ? std::string(" (it is empty)") : std::string(" (no PNG signature)")));
    // The header chunk (IHDR) must come first: length at byte 8, type at 12, then width, height, bit depth,
    // colour type. Checked here, before the decoder allocates anything.
    if (bytes.size() < 8 + 8 + 13 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0)
        throw Error("depth image " + source + " is truncated or corrupt (no PNG header chunk; " +
                    std::to_string(bytes.size()) + " bytes)");
    auto be32 = [&](size_t o) {
        return uint32_t(uint8_t(bytes[o])) << 24 | uint32_t(uint8_t(bytes[o + 1])) << 16 |
               uint32_t(uint8_t(bytes[o + 2])) << 8 | uint32_t(uint8_t(bytes[o + 3]));
    };
    const uint32_t w = be32(16), h = be32(20);
    const int bitDepth = uint8_t(bytes[24]), colorType = uint8_t(bytes[25]);
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    if (w == 0 || h == 0) throw Error("depth image " + source + " is corrupt: its header says " + size + " pixels");
    if (w > kMaxDepthImageSide || h > kMaxDepthImageSide || uint64_t(w) * h > kMaxDepthImagePixels)
        throw Error("depth image " + source + " claims " + size + " pixels, more than vkmesh accepts (" +
                    std::to_string(kMaxDepthImageSide) + " per side, " + std::to_string(kMaxDepthImagePixels >> 20) +
                    " Mpixel); the file is corrupt or not a depth image");
    if (bitDepth != 16 || colorType != 0)
        throw Error("depth image " + source + " is " + describePng(bitDepth, colorType) + " (" + size +
                    "); expected 16-bit unsigned, 1 channel (a 16-bit grayscale PNG)");
    if (bytes.size() > size_t(std::numeric_limits<int>::max()))
        throw Error("depth image " + source + " is " + std::to_string(bytes.size()) + " bytes, too large to be a depth image");
    cv::Mat img;
    try {
        const cv::Mat buffer(1, int(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
        img = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        throw Error("cannot decode depth image " + source + ": " + e.what());
    }
    if (img.empty()) throw Error("cannot decode depth image " + source + " (truncated or corrupt)");
    if (img.type() != CV_16UC1)
        throw Error("depth image " + source + " is " + describeType(img) + " (" + std::to_string(img.cols) + "x" +
                    std::to_string(img.rows) + "); expected 16-bit unsigned, 1 channel");
    if (img.cols != int(w) || img.rows != int(h))
        throw Error("depth image " + source + " decodes to " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                    " but its header says " + size);
    return img;
}

void rawDepthToMeters(const uint16_t* raw, int width, int height, size_t rowStride, double depthScale,
                      std::optional<uint16_t> invalidRaw, float maxDepth, DepthImage& out) {
    out.width = width;
    out.height = height;
    out.meters.resize(static_cast<size_t>(width) * height);
    const uint16_t invalid = invalidRaw.value_or(0);
    for (int y = 0; y < height; ++y) {
        const uint16_t* row = raw + static_cast<size_t>(y) * rowStride;
        float* dst = out.meters.data() + static_cast<size_t>(y) * width;
        for (int x = 0; x < width; ++x) {
            uint16_t v = row[x];
            float m = (v == 0 || v == invalid) ? 0.0f : static_cast<float>(v / depthScale);
            if (maxDepth > 0 && m > maxDepth) m = 0.0f;
            dst[x] = m;
        }
    }
}

DepthImage rawDepthToMeters(const cv::Mat& raw, double depthScale, std::optional<uint16_t> invalidRaw, float maxDepth) {
    DepthImage out;
    rawDepthToMeters(raw.ptr<uint16_t>(0), raw.cols, raw.rows, raw.step1(), depthScale, invalidRaw, maxDepth, out);
    return out;
}

namespace {

uint32_t be16(std::string_view b, size_t o) { return uint32_t(uint8_t(b[o])) << 8 | uint32_t(uint8_t(b[o + 1])); }

// Width and height from a JPEG's frame header (SOFn), found by walking the marker segments before the scan;
// nothing when the segments are corrupt or end first.
std::optional<std::pair<uint32_t, uint32_t>> jpegSize(std::string_view b) {
    size_t o = 2;  // after the SOI marker FF D8
    while (o + 4 <= b.size()) {
        if (uint8_t(b[o]) != 0xFF) return std::nullopt;
        const uint8_t marker = uint8_t(b[o + 1]);
        if (marker == 0xFF) {  // fill byte
            ++o;
            continue;
        }
        if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {  // no length
            o += 2;
            continue;
        }
        const uint32_t length = be16(b, o + 2);
        if (length < 2) return std::nullopt;
        const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (sof) {
            if (o + 9 > b.size()) return std::nullopt;
            return std::make_pair(be16(b, o + 7), be16(b, o + 5));
        }
        if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan or end before any frame header
        o += 2 + length;
    }
    return std::nullopt;
}

}  // namespace

ColorImage decodeColorImage(std::string_view bytes, const std::string& source) {
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    const bool isPng = bytes.size() >= 8 && std::memcmp(bytes.data(), png, 8) == 0;
    const bool isJpeg = bytes.size() >= 3 && uint8_t(bytes[0]) == 0xFF && uint8_t(bytes[1]) == 0xD8 && uint8_t(bytes[2]) == 0xFF;
    if (!isPng && !isJpeg)
        throw Error("colour image " + source + " is neither a PNG nor a JPEG file" +
                    (bytes.empty() ? std::string(" (it is empty)") : std::string(" (no PNG or JPEG signature)")));
    // The size from the header, checked before the decoder allocates anything (as for depth).
    uint32_t w = 0, h = 0;
    if (isPng) {
        if (bytes.size() < 8 + 8 + 13 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0)
            throw Error("colour image " + source + " is truncated or corrupt (no PNG header chunk; " +
                        std::to_string(bytes.size()) + " bytes)");
        w = be16(bytes, 16) << 16 | be16(bytes, 18);
        h = be16(bytes, 20) << 16 | be16(bytes, 22);
        const int bitDepth = uint8_t(bytes[24]), colorType = uint8_t(bytes[25]);
        if (bitDepth == 16)
            throw Error("colour image " + source + " is " + describePng(bitDepth, colorType) +
                        "; expected 8 bits per channel (is it a depth image?)");
    } else {
        const auto size = jpegSize(bytes);
        if (!size) throw Error("colour image " + source + " is a truncated or corrupt JPEG (no frame header)");
        std::tie(w, h) = *size;
    }
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    if (w == 0 || h == 0) throw Error("colour image " + source + " is corrupt: its header says " + size + " pixels");
    if (w > kMaxDepthImageSide || h > kMaxDepthImageSide || uint64_t(w) * h > kMaxDepthImagePixels)
        throw Error("colour image " + source + " claims " + size + " pixels, more than vkmesh accepts (" +
                    std::to_string(kMaxDepthImageSide) + " per side, " + std::to_string(kMaxDepthImagePixels >> 20) +
                    " Mpixel)");
    if (bytes.size() > size_t(std::numeric_limits<int>::max()))
        throw Error("colour image " + source + " is " + std::to_string(bytes.size()) + " bytes, too large");
    cv::Mat img;
    try {
        const cv::Mat buffer(1, int(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
        // UNCHANGED: no EXIF rotation (the image must stay on the depth camera's grid), no silent 16 -> 8 bits.
        img = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        throw Error("cannot decode colour image " + source + ": " + e.what());
    }
    if (img.empty()) throw Error("cannot decode colour image " + source + " (truncated or corrupt)");
    if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3 && img.channels() != 4))
        throw Error("colour image " + source + " is " + describeType(img) + " (" + std::to_string(img.cols) + "x" +
                    std::to_string(img.rows) + "); expected 8-bit with 1, 3 or 4 channels");
    ColorImage out;
    out.width = img.cols;
    out.height = img.rows;
    out.rgb.resize(size_t(img.cols) * img.rows * 3);
    const int c = img.channels();
    for (int y = 0; y < img.rows; ++y) {
        const uint8_t* row = img.ptr<uint8_t>(y);
        uint8_t* dst = out.rgb.data() + size_t(y) * img.cols * 3;
        for (int x = 0; x < img.cols; ++x, dst += 3) {
            const uint8_t* p = row + size_t(x) * c;
            if (c == 1) {
                dst[0] = dst[1] = dst[2] = p[0];
            } else {  // OpenCV's order is B, G, R (, A)
                dst[0] = p[2];
                dst[1] = p[1];
                dst[2] = p[0];
            }
        }
    }
    return out;
}

}  // namespace io

namespace {

// ---------------------------------------------------------------------------------------------------
// What a layout reader hands back to Dataset::open before the common steps (calibration overrides,
// maxFrames, reading frame 0).

struct Candidate {
    double timestamp;
    fs::path depthPath;
    std::string origin;  // where the frame was listed, for messages ("depth.txt:12", "depth/000003.png")
};

struct Layout {
    DatasetKind kind = DatasetKind::TUM;
    // The layout's default calibration: a camera preset (data/cameras/<name>/camera.json), read by
    // Dataset::open only when the folder's camera.json and the options leave a value to it.
    std::string preset;
    std::optional<Intrinsics> folderIntrinsics;  // the sequence's own calibration file (7-Scenes)
    std::string intrinsicsWarning;  // set when the default is a guess rather than the sequence's calibration
    std::optional<uint16_t> invalidRaw;
    std::vector<FrameInfo> frames;  // frames with a pose, in time order
    std::vector<std::string> warnings;
    size_t skipped = 0;
    size_t framesWithoutColor = 0;  // in a layout that has colour
};

// Per-frame warnings are capped so that a sequence with a long tracking gap does not flood the log.
constexpr size_t kMaxFrameWarnings = 20;

// A depth frame that gets no colour image (it is fused without colour); capped like skipped frames.
void warnNoColor(Layout& layout, const std::string& message) {
    if (layout.framesWithoutColor < kMaxFrameWarnings) layout.warnings.push_back(message);
    ++layout.framesWithoutColor;
}

void warnSkipped(Layout& layout, const std::string& message) {
    if (layout.skipped < kMaxFrameWarnings) layout.warnings.push_back(message);
    ++layout.skipped;
}

void summariseSkipped(Layout& layout, size_t listed, const std::string& why) {
    if (layout.skipped > kMaxFrameWarnings)
        layout.warnings.push_back("... and " + std::to_string(layout.skipped - kMaxFrameWarnings) +
                                  " more skipped frames");
    if (layout.skipped > 0)
        layout.warnings.push_back("skipped " + std::to_string(layout.skipped) + " of " + std::to_string(listed) +
                                  " depth frames (" + why + ")");
}

// ---------------------------------------------------------------------------------------------------
// TUM RGB-D and ICL-NUIM (TUM-compatible release)

struct Stamped {
    double t;
    size_t line;
    fs::path path;  // depth entries only
    Pose pose;      // groundtruth entries only
};

std::vector<Stamped> stamped(const std::vector<io::TimedPath>& v) {
    std::vector<Stamped> out;
    out.reserve(v.size());
    for (const auto& e : v) out.push_back({e.timestamp, e.line, e.path, Pose::Identity()});
    return out;
}

std::vector<Stamped> readDepthList(const fs::path& folder, const fs::path& file) {
    std::ifstream in = openText(file);
    return stamped(io::parseDepthList(in, file.string(), folder));
}

std::vector<Stamped> readAssociations(const fs::path& folder, const fs::path& file) {
    std::ifstream in = openText(file);
    return stamped(io::parseAssociations(in, file.string(), folder));
}

std::vector<Stamped> readGroundtruth(const fs::path& file) {
    std::ifstream in = openText(file);
    std::vector<Stamped> out;
    for (auto& p : io::parseTrajectory(in, file.string())) out.push_back({p.timestamp, p.line, {}, p.cameraToWorld});
    return out;
}

// Sorts by time (unsorted files are legitimate) and drops repeated timestamps, keeping the entry that
// came first in the file. Returns how many were dropped.
size_t sortAndDedupe(std::vector<Stamped>& v, const fs::path& file, std::vector<std::string>& warnings) {
    std::stable_sort(v.begin(), v.end(), [](const Stamped& a, const Stamped& b) { return a.t < b.t; });
    std::vector<Stamped> kept;
    kept.reserve(v.size());
    size_t dropped = 0;
    for (auto& s : v) {
        if (!kept.empty() && kept.back().t == s.t) {
            if (dropped < kMaxFrameWarnings)
                warnings.push_back(at(file, s.line) + ": timestamp " + fmtTime(s.t) + " repeats line " +
                                   std::to_string(kept.back().line) + "; kept the first");
            ++dropped;
            continue;
        }
        kept.push_back(std::move(s));
    }
    v = std::move(kept);
    return dropped;
}

// ICL-NUIM's TUM-compatible files use frame indices as timestamps; TUM uses Unix time (~1.3e9 s).
bool timestampsAreFrameIndices(const std::vector<Stamped>& depth) {
    if (depth.empty()) return false;
    for (const auto& s : depth)
        if (s.t < 0 || s.t >= 1e6 || s.t != std::floor(s.t)) return false;
    return true;
}

Layout readTum(const fs::path& folder, const std::string& folderName) {
    Layout layout;
    fs::path depthFile = folder / "depth.txt";
    fs::path gtFile = folder / "groundtruth.txt";
    std::error_code ec;
    // depth.txt is authoritative; associations.txt is a derived file, used only when it is all there is.
    fs::path listFile = fs::is_regular_file(depthFile, ec) ? depthFile : folder / "associations.txt";
    if (!fs::is_regular_file(gtFile, ec))
        throw Error("TUM/ICL-NUIM layout in " + folder.string() + ": found " + listFile.filename().string() +
                    " but no groundtruth.txt with the camera poses");

    std::vector<Stamped> depth = listFile == depthFile ? readDepthList(folder, listFile) : readAssociations(folder, listFile);
    if (depth.empty()) throw Error(listFile.string() + " lists no depth frames");
    std::vector<Stamped> gt = readGroundtruth(gtFile);
    if (gt.empty()) throw Error(gtFile.string() + " has no poses");

    const size_t listed = depth.size();
    layout.skipped = sortAndDedupe(depth, listFile, layout.warnings);
    sortAndDedupe(gt, gtFile, layout.warnings);

    auto namesSensor = [&](int sensor) {
        std::string n = std::to_string(sensor);
        return containsWord(folderName, "freiburg" + n) || containsWord(folderName, "fr" + n);
    };
    const int tumSensor = namesSensor(1) ? 1 : namesSensor(2) ? 2 : namesSensor(3) ? 3 : 0;
    // The folder name is the primary clue (the shared copy is "iclnuim_office_traj0"); frame-index
    // timestamps catch ICL-NUIM folders renamed after their scene ("living_room_traj0_frei_png"), unless
    // the name says which TUM sensor recorded the sequence.
    bool icl = containsWord(folderName, "icl") || (tumSensor == 0 && timestampsAreFrameIndices(depth));
    layout.kind = icl ? DatasetKind::ICLNUIM : DatasetKind::TUM;
    // The default calibration is a preset in data/cameras/ (ICL-NUIM's fy is negative: its poses are for a
    // camera whose image y axis points up).
    if (icl) {
        layout.preset = "icl_nuim";
    } else if (tumSensor != 0) {
        layout.preset = "tum_fr" + std::to_string(tumSensor);
    } else {
        layout.preset = "tum_default";
        // Dataset::open appends the preset's values.
        layout.intrinsicsWarning = "folder name '" + folderName +
                                   "' names no TUM sensor (freiburg1/2/3 or fr1/2/3); using the default intrinsics";
    }

    // TUM's motion capture runs at ~100 Hz, so a pose within 20 ms exists unless tracking dropped out;
    // ICL-NUIM's timestamps are frame indices and must match exactly.
    const double tolerance = icl ? 0.5 : 0.020;
    const std::string tolText = icl ? "the same frame index" : "20 ms";
    for (const auto& d : depth) {
        auto it = std::lower_bound(gt.begin(), gt.end(), d.t, [](const Stamped& g, double t) { return g.t < t; });
        const Stamped* best = nullptr;
        if (it != gt.end()) best = &*it;
        if (it != gt.begin() && (!best || d.t - std::prev(it)->t < best->t - d.t)) best = &*std::prev(it);
        double dt = std::abs(best->t - d.t);
        bool near = icl ? dt < tolerance : dt <= tolerance;  // strict for ICL: 0.5 would be a tie
        if (!near) {
            warnSkipped(layout, at(listFile, d.line) + ": depth frame " + fmtTime(d.t) + " (" + d.path.filename().string() +
                                    ") has no pose within " + tolText + " in groundtruth.txt (nearest is " +
                                    (icl ? fmt(dt) + " frames" : fmtFixed(dt * 1000.0, 1) + " ms") + " away); skipped");
            continue;
        }
        FrameInfo f;
        f.timestamp = d.t;
        f.depthPath = d.path;
        f.cameraToWorld = best->pose;
        layout.frames.push_back(std::move(f));
    }
    if (layout.frames.empty())
        throw Error("none of the " + std::to_string(depth.size()) + " depth frames in " + listFile.string() +
                    " (timestamps " + fmtTime(depth.front().t) + " .. " + fmtTime(depth.back().t) + ") has a pose within " +
                    tolText + " in " + gtFile.string() + " (timestamps " + fmtTime(gt.front().t) + " .. " +
                    fmtTime(gt.back().t) + ")");
    summariseSkipped(layout, listed, "no pose within " + tolText + ", or a repeated timestamp");

    // Colour: rgb.txt, the image nearest in time to each depth frame (the sensor streams are not
    // synchronised in TUM; ICL-NUIM's share the frame index). Colour is optional: a broken rgb.txt costs
    // the colour, not the reconstruction.
    const fs::path rgbFile = folder / "rgb.txt";
    if (fs::is_regular_file(rgbFile, ec)) {
        std::vector<Stamped> rgb;
        try {
            rgb = readDepthList(folder, rgbFile);
        } catch (const Error& e) {
            layout.warnings.push_back(std::string(e.what()) + "; colour ignored");
        }
        sortAndDedupe(rgb, rgbFile, layout.warnings);
        for (FrameInfo& f : layout.frames) {
            if (rgb.empty()) break;
            auto it = std::lower_bound(rgb.begin(), rgb.end(), f.timestamp, [](const Stamped& c, double t) { return c.t < t; });
            const Stamped* best = it != rgb.end() ? &*it : nullptr;
            if (it != rgb.begin() && (!best || f.timestamp - std::prev(it)->t < best->t - f.timestamp)) best = &*std::prev(it);
            const double dt = std::abs(best->t - f.timestamp);
            if (icl ? dt < tolerance : dt <= tolerance) {
                f.colorPath = best->path;
            } else {
                warnNoColor(layout, rgbFile.string() + ": no colour image within " + tolText + " of depth frame " +
                                        fmtTime(f.timestamp) + " (" + f.depthPath.filename().string() + "; nearest is " +
                                        (icl ? fmt(dt) + " frames" : fmtFixed(dt * 1000.0, 1) + " ms") +
                                        " away); that frame has no colour");
            }
        }
    }
    return layout;
}

// ---------------------------------------------------------------------------------------------------
// Redwood / Zhou-Koltun: a *.log trajectory + depth/*.png (millimetres)

std::vector<fs::path> filesWithExtension(const fs::path& dir, const std::string& ext) {
    std::vector<fs::path> out;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.is_regular_file(ec) && lower(e.path().extension().string()) == ext) out.push_back(e.path());
    std::sort(out.begin(), out.end(),
              [](const fs::path& a, const fs::path& b) { return naturalLess(a.filename().string(), b.filename().string()); });
    return out;
}

Layout readRedwood(const fs::path& folder, const fs::path& logFile) {
    Layout layout;
    layout.kind = DatasetKind::Redwood;
    layout.preset = "redwood";  // PrimeSense defaults, depth in millimetres

    std::vector<fs::path> images = filesWithExtension(folder / "depth", ".png");
    if (images.empty()) throw Error("Redwood layout: " + (folder / "depth").string() + " holds no .png depth images");

    // Blocks of five lines: "id id frame" then the camera-to-world matrix. The first id is the 0-based
    // index of the depth image (in name order) the pose belongs to.
    std::ifstream logIn = openText(logFile);
    std::map<long long, std::pair<Pose, size_t>> poses;  // id -> pose, line of its header
    size_t duplicates = 0;
    for (const io::IndexedPose& p : io::parseRedwoodLog(logIn, logFile.string())) {
        if (!poses.emplace(p.id, std::make_pair(p.cameraToWorld, p.line)).second) {
            if (duplicates++ < kMaxFrameWarnings)
                layout.warnings.push_back(at(logFile, p.line) + ": frame " + std::to_string(p.id) +
                                          " appears again; kept the first pose");
        }
    }
    if (poses.empty()) throw Error(logFile.string() + " has no poses");

    for (size_t k = 0; k < images.size(); ++k) {
        auto it = poses.find(static_cast<long long>(k));
        if (it == poses.end()) {
            warnSkipped(layout, (fs::path("depth") / images[k].filename()).string() + ": frame " + std::to_string(k) +
                                    " has no pose in " + logFile.filename().string() + "; skipped");
            continue;
        }
        FrameInfo f;
        f.timestamp = static_cast<double>(k);
        f.depthPath = images[k];
        f.cameraToWorld = it->second.first;
        layout.frames.push_back(std::move(f));
    }
    size_t orphans = 0;
    for (const auto& [id, p] : poses)
        if (id < 0 || static_cast<size_t>(id) >= images.size()) ++orphans;
    if (orphans > 0)
        layout.warnings.push_back(std::to_string(orphans) + " poses in " + logFile.filename().string() +
                                  " name frames beyond the " + std::to_string(images.size()) +
                                  " images in depth/; ignored");
    if (layout.frames.empty())
        throw Error("none of the " + std::to_string(images.size()) + " images in " + (folder / "depth").string() +
                    " has a pose in " + logFile.string() + " (frame ids " + std::to_string(poses.begin()->first) +
                    " .. " + std::to_string(poses.rbegin()->first) + ")");
    summariseSkipped(layout, images.size(), "no pose in " + logFile.filename().string());

    // Colour: color/ (Redwood) or rgb/ (some converters) beside depth/, paired by position in name order.
    for (const char* name : {"color", "rgb"}) {
        std::vector<fs::path> colors;
        for (const char* ext : {".jpg", ".jpeg", ".png"})
            for (fs::path& p : filesWithExtension(folder / name, ext)) colors.push_back(std::move(p));
        if (colors.empty()) continue;
        std::sort(colors.begin(), colors.end(), [](const fs::path& a, const fs::path& b) {
            return naturalLess(a.filename().string(), b.filename().string());
        });
        if (colors.size() != images.size())
            layout.warnings.push_back((folder / name).string() + " holds " + std::to_string(colors.size()) +
                                      " colour images for " + std::to_string(images.size()) +
                                      " depth images; paired by name order, extra depth frames have no colour");
        for (FrameInfo& f : layout.frames) {
            const size_t k = static_cast<size_t>(f.timestamp);  // the depth image's position in name order
            if (k < colors.size()) f.colorPath = colors[k];
        }
        break;
    }
    return layout;
}

// ---------------------------------------------------------------------------------------------------
// 7-Scenes: frame-NNNNNN.depth.png + frame-NNNNNN.pose.txt (millimetres, 0 and 65535 invalid)

struct SevenScenesFrame {
    long long number;
    fs::path depth;
};

std::vector<SevenScenesFrame> listSevenScenesFrames(const fs::path& dir) {
    static const std::string prefix = "frame-", suffix = ".depth.png";
    std::vector<SevenScenesFrame> out;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        std::string name = e.path().filename().string();
        if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        long long n;
        std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
        if (!parseInteger(digits, n) || !std::all_of(digits.begin(), digits.end(), [](unsigned char ch) { return std::isdigit(ch); })) continue;
        out.push_back({n, e.path()});
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.number < b.number; });
    return out;
}

std::vector<double> readNumbers(const fs::path& file, size_t count, const std::string& what) {
    std::ifstream in = openText(file);
    return io::parseNumbers(in, file.string(), count, what);
}

Layout readSevenScenes(const fs::path& folder, const std::vector<SevenScenesFrame>& images) {
    Layout layout;
    layout.kind = DatasetKind::SevenScenes;
    layout.preset = "seven_scenes";  // depth in millimetres
    layout.invalidRaw = 65535;  // the Kinect's "no reading" marker in 7-Scenes, besides 0

    // Calibration may sit beside the frames or, for a seq-XX folder, in the scene folder above it.
    for (const fs::path& dir : {folder, folder.parent_path()}) {
        fs::path kFile = dir / "camera-intrinsics.txt";
        std::error_code ec;
        if (!fs::is_regular_file(kFile, ec)) continue;
        std::vector<double> K = readNumbers(kFile, 9, "a 3x3 camera matrix");
        for (double v : K)
            if (!std::isfinite(v)) throw Error(kFile.string() + ": value " + fmt(v) + " is not finite");
        if (K[0] <= 0 || K[4] <= 0)
            throw Error(kFile.string() + ": focal length fx=" + fmt(K[0]) + " fy=" + fmt(K[4]) + " must be positive");
        layout.folderIntrinsics = Intrinsics{float(K[0]), float(K[4]), float(K[2]), float(K[5]), 0, 0};
        break;
    }

    for (const auto& img : images) {
        std::string stem = img.depth.filename().string();
        stem.resize(stem.size() - std::string(".depth.png").size());
        fs::path poseFile = folder / (stem + ".pose.txt");
        std::error_code ec;
        if (!fs::is_regular_file(poseFile, ec)) {
            warnSkipped(layout, img.depth.filename().string() + ": no " + poseFile.filename().string() + "; skipped");
            continue;
        }
        std::vector<double> m = readNumbers(poseFile, 16, "a 4x4 camera-to-world matrix");
        Pose T;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) T(r, c) = m[r * 4 + c];
        validatePose(T, poseFile.string() + " (frame " + std::to_string(img.number) + ")");
        FrameInfo f;
        f.timestamp = static_cast<double>(img.number);
        f.depthPath = img.depth;
        f.cameraToWorld = T;
        for (const char* ext : {".color.png", ".color.jpg"})
            if (fs::is_regular_file(folder / (stem + ext), ec)) {
                f.colorPath = folder / (stem + ext);
                break;
            }
        if (f.colorPath.empty()) ++layout.framesWithoutColor;
        layout.frames.push_back(std::move(f));
    }
    if (layout.framesWithoutColor > 0 && layout.framesWithoutColor < layout.frames.size())
        layout.warnings.push_back(std::to_string(layout.framesWithoutColor) + " of " +
                                  std::to_string(layout.frames.size()) +
                                  " frames have no frame-NNNNNN.color.png or .color.jpg; they have no colour");
    if (layout.frames.empty())
        throw Error("none of the " + std::to_string(images.size()) + " frame-*.depth.png files in " + folder.string() +
                    " has a matching frame-*.pose.txt");
    summariseSkipped(layout, images.size(), "no pose file");
    return layout;
}

// ---------------------------------------------------------------------------------------------------
// Layout detection

// Which layout's files a folder holds; picks the reader, and finds datasets in subfolders for the
// error message when the user passes a parent folder.
struct LayoutFiles {
    bool tumList = false;              // depth.txt or associations.txt
    std::vector<fs::path> logs;        // *.log trajectories
    bool depthDir = false;             // depth/ (Redwood)
    std::vector<SevenScenesFrame> seven;
    bool redwood() const { return !logs.empty() && depthDir; }
    bool any() const { return tumList || redwood() || !seven.empty(); }
};

LayoutFiles scanLayout(const fs::path& dir) {
    LayoutFiles f;
    std::error_code ec;
    f.tumList = fs::is_regular_file(dir / "depth.txt", ec) || fs::is_regular_file(dir / "associations.txt", ec);
    f.logs = filesWithExtension(dir, ".log");
    f.depthDir = fs::is_directory(dir / "depth", ec);
    f.seven = listSevenScenesFrames(dir);
    return f;
}

// ---------------------------------------------------------------------------------------------------
// camera.json: {"fx":..,"fy":..,"cx":..,"cy":..,"depth_scale":..}, every key optional

io::CameraJson readCameraJson(const fs::path& file) {
    std::ifstream in = openText(file);
    return io::parseCameraJson(in, file.string());
}

}  // namespace

void checkIntrinsics(const Intrinsics& k, const std::string& source) {
    auto check = [&](const char* name, float v, bool nonZero) {
        if (!std::isfinite(v)) throw Error(source + ": " + name + " = " + fmt(v) + " is not finite");
        if (nonZero && v == 0) throw Error(source + ": " + name + " = 0; it must be non-zero");
    };
    check("fx", k.fx, true);
    check("fy", k.fy, true);
    // A negative fx mirrors the image left-right; no supported layout uses one. A negative fy is ICL-NUIM's
    // convention (image y up) and is checked against the layout in Dataset::open.
    if (k.fx < 0) throw Error(source + ": fx = " + fmt(k.fx) + " is negative; it must be positive");
    check("cx", k.cx, false);
    check("cy", k.cy, false);
}

// =====================================================================================================

std::string toString(DatasetKind kind) {
    switch (kind) {
        case DatasetKind::TUM: return "TUM RGB-D";
        case DatasetKind::ICLNUIM: return "ICL-NUIM";
        case DatasetKind::Redwood: return "Redwood";
        case DatasetKind::SevenScenes: return "7-Scenes";
    }
    return "unknown";
}

CameraPreset loadCameraPreset(const std::string& name) {
    CameraPreset preset;
    preset.name = name;
    preset.file = io::findDataFile("cameras/" + name + "/camera.json");
    std::ifstream in = openText(preset.file);
    const io::CameraJson c = io::parseCameraJson(in, preset.file.string());
    // A preset is the product's own file: every value stated, nothing unknown (a typo must not fall back).
    std::string missing;
    for (const auto& [key, value] : {std::pair<const char*, bool>{"fx", bool(c.fx)}, {"fy", bool(c.fy)}, {"cx", bool(c.cx)},
                                     {"cy", bool(c.cy)}, {"depth_scale", bool(c.depthScale)}})
        if (!value) missing += (missing.empty() ? "" : ", ") + std::string(key);
    if (!missing.empty()) throw Error(preset.file.string() + ": a camera preset must give fx, fy, cx, cy and depth_scale; missing " + missing);
    if (!c.ignoredKeys.empty()) throw Error(preset.file.string() + ": unknown key " + c.ignoredKeys.front() + " in a camera preset");
    preset.intrinsics = {float(*c.fx), float(*c.fy), float(*c.cx), float(*c.cy), c.width.value_or(0), c.height.value_or(0)};
    checkIntrinsics(preset.intrinsics, preset.file.string());
    preset.depthScale = *c.depthScale;
    return preset;
}

Intrinsics parseIntrinsics(const std::string& text) {
    std::vector<std::string> parts;
    std::string cur;
    for (char ch : text) {
        if (ch == ',') {
            parts.push_back(cur);
            cur.clear();
        } else if (!std::isspace(static_cast<unsigned char>(ch))) {
            cur += ch;
        }
    }
    parts.push_back(cur);
    if (parts.size() != 4)
        throw Error("intrinsics '" + text + "': expected four comma-separated numbers fx,fy,cx,cy, got " +
                    std::to_string(parts.size()));
    static const char* names[] = {"fx", "fy", "cx", "cy"};
    double v[4];
    for (int i = 0; i < 4; ++i) {
        if (!parseNumber(parts[i], v[i]))
            throw Error("intrinsics '" + text + "': " + names[i] + " '" + parts[i] + "' is not a number");
        if (!std::isfinite(v[i]))
            throw Error("intrinsics '" + text + "': " + names[i] + " '" + parts[i] + "' is not finite");
    }
    Intrinsics k;
    k.fx = float(v[0]);
    k.fy = float(v[1]);
    k.cx = float(v[2]);
    k.cy = float(v[3]);
    checkIntrinsics(k, "intrinsics '" + text + "'");
    return k;
}

void validatePose(const Pose& pose, const std::string& where) {
    if (!pose.allFinite()) throw Error(where + ": pose has non-finite entries");
    Eigen::RowVector4d bottom = pose.row(3);
    // Files write the last row as literal 0 0 0 1; allow only print rounding.
    if ((bottom - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
        throw Error(where + ": pose bottom row is " + fmt(bottom[0]) + " " + fmt(bottom[1]) + " " + fmt(bottom[2]) +
                    " " + fmt(bottom[3]) + "; expected 0 0 0 1");
    Eigen::Matrix3d R = pose.topLeftCorner<3, 3>();
    double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (err > 1e-3)
        throw Error(where + ": pose rotation is not orthonormal (max |R^T R - I| = " + fmt(err) + ")");
    // Orthonormal leaves det = +1 (rotation) or -1 (a mirror, e.g. a flipped axis convention).
    if (R.determinant() < 0) throw Error(where + ": pose rotation has determinant -1 (a reflection, not a rotation)");
}

std::unique_ptr<Dataset> Dataset::open(const fs::path& folderIn, const DatasetOptions& options) {
    // Options first: a bad command-line value is reported before any file is touched.
    if (options.depthScale && !(std::isfinite(*options.depthScale) && *options.depthScale > 0))
        throw Error("depth scale " + fmt(*options.depthScale) + " must be a positive finite number");
    if (!(std::isfinite(options.maxDepth) && options.maxDepth >= 0))
        throw Error("max depth " + fmt(options.maxDepth) + " must be a finite number >= 0 (0 = no limit)");
    if (options.intrinsics) checkIntrinsics(*options.intrinsics, "--intrinsics");

    std::error_code ec;
    if (!fs::exists(folderIn, ec)) throw Error("dataset folder " + folderIn.string() + " does not exist");
    if (!fs::is_directory(folderIn, ec)) throw Error("dataset path " + folderIn.string() + " is not a folder");
    // Canonical so that "seq/", "." or a symlink still give the real folder name, which carries the
    // sequence name that selects TUM/ICL intrinsics.
    fs::path folder = fs::weakly_canonical(fs::absolute(folderIn), ec);
    if (ec) folder = fs::absolute(folderIn).lexically_normal();
    std::string folderName = lower(folder.filename().string());

    // --- detect the layout ---
    Layout layout;
    LayoutFiles files = scanLayout(folder);
    if (files.tumList) {
        layout = readTum(folder, folderName);
    } else if (files.redwood()) {
        if (files.logs.size() > 1) {
            std::string names;
            for (const auto& l : files.logs) names.append(names.empty() ? "" : " ").append(l.filename().string());
            throw Error("Redwood layout in " + folder.string() + ": several .log trajectories (" + names +
                        "); keep one");
        }
        layout = readRedwood(folder, files.logs.front());
    } else if (!files.seven.empty()) {
        layout = readSevenScenes(folder, files.seven);
    } else {
        const std::string lookedFor =
            "looked for: depth.txt or associations.txt with groundtruth.txt (TUM RGB-D, ICL-NUIM), "
            "a *.log trajectory with a depth/ folder of PNGs (Redwood), "
            "frame-NNNNNN.depth.png with frame-NNNNNN.pose.txt (7-Scenes)";
        // A parent folder (a 7-Scenes scene with seq-XX folders, a folder of sequences) is a common
        // mistake; which sequence to fuse is the user's choice, so name the candidates instead of guessing.
        std::vector<std::string> subs;
        for (const auto& e : fs::directory_iterator(folder, ec))
            if (e.is_directory(ec) && scanLayout(e.path()).any()) subs.push_back(e.path().filename().string());
        std::sort(subs.begin(), subs.end(), naturalLess);
        if (!subs.empty()) {
            std::string list;
            for (const auto& n : subs) list.append(list.empty() ? "" : ", ").append(n);
            throw Error("no dataset directly in " + folder.string() + ", but its subfolders " + list +
                        " hold one each; pass one of them, e.g. " + (folder / subs.front()).string() + " (" +
                        lookedFor + ")");
        }
        throw Error("no recognised dataset layout in " + folder.string() + "; " + lookedFor);
    }

    std::unique_ptr<Dataset> ds(new Dataset());
    ds->kind_ = layout.kind;
    ds->folder_ = folder;
    ds->invalidRaw_ = layout.invalidRaw;
    ds->maxDepth_ = options.maxDepth;
    ds->warnings_ = std::move(layout.warnings);
    ds->skippedFrames_ = layout.skipped;

    // --- calibration: DatasetOptions > camera.json > the sequence's own file (7-Scenes) > the layout's preset ---
    fs::path cameraJson = folder / "camera.json";
    std::optional<io::CameraJson> camera;
    if (fs::is_regular_file(cameraJson, ec)) {
        camera = readCameraJson(cameraJson);
        if (!camera->ignoredKeys.empty()) {
            std::string keys;
            for (const auto& key : camera->ignoredKeys) keys += (keys.empty() ? "" : ", ") + key;
            ds->warnings_.push_back(cameraJson.string() + ": ignored unknown keys " + keys +
                                    " (known: fx, fy, cx, cy, depth_scale, width, height, color_fx, color_fy, color_cx, color_cy, "
                                    "color_width, color_height)");
        }
    }
    // The preset is read only when something is left to it, so that a fully calibrated folder needs no data files.
    const bool intrinsicsGiven = options.intrinsics || (camera && camera->hasAllIntrinsics()) || layout.folderIntrinsics;
    const bool scaleGiven = options.depthScale || (camera && camera->depthScale);
    Intrinsics k;
    double scale = 0;
    if (!intrinsicsGiven || !scaleGiven) {
        const CameraPreset preset = loadCameraPreset(layout.preset);
        k = preset.intrinsics;
        scale = preset.depthScale;
        if (!intrinsicsGiven && !layout.intrinsicsWarning.empty())
            ds->warnings_.push_back(layout.intrinsicsWarning + " " + fmt(k.fx) + " " + fmt(k.fy) + " " + fmt(k.cx) + " " +
                                    fmt(k.cy) + " (give --intrinsics or a camera.json)");
    }
    if (layout.folderIntrinsics) k = *layout.folderIntrinsics;
    if (camera) {
        const io::CameraJson& c = *camera;
        if (c.fx) k.fx = float(*c.fx);
        if (c.fy) k.fy = float(*c.fy);
        if (c.cx) k.cx = float(*c.cx);
        if (c.cy) k.cy = float(*c.cy);
        if (c.depthScale) scale = *c.depthScale;
    }
    if (options.intrinsics) {
        k.fx = options.intrinsics->fx;
        k.fy = options.intrinsics->fy;
        k.cx = options.intrinsics->cx;
        k.cy = options.intrinsics->cy;
    }
    if (options.depthScale) scale = *options.depthScale;
    // A negative fy flips the image vertically: right for ICL-NUIM's poses (its default has one), a mirrored
    // reconstruction anywhere else.
    if (k.fy < 0 && layout.kind != DatasetKind::ICLNUIM)
        throw Error(std::string(options.intrinsics ? "--intrinsics" : cameraJson.string()) + ": fy = " + fmt(k.fy) +
                    " is negative, which mirrors the " + toString(layout.kind) +
                    " reconstruction upside down (only ICL-NUIM's poses use a negative fy); give a positive fy");
    ds->depthScale_ = scale;

    // --- frames ---
    if (options.maxFrames > 0 && layout.frames.size() > options.maxFrames) layout.frames.resize(options.maxFrames);
    for (size_t i = 0; i < layout.frames.size(); ++i) {
        layout.frames[i].index = i;
        // A listed file that is missing fails now rather than minutes into a reconstruction.
        if (!fs::is_regular_file(layout.frames[i].depthPath, ec))
            throw Error("depth image " + layout.frames[i].depthPath.string() + " (frame " + std::to_string(i) +
                        ") does not exist");
    }
    // Colour files that are listed but missing are found now, like depth, but cost only that frame's colour.
    size_t withColor = 0, missingColor = 0;
    for (FrameInfo& f : layout.frames) {
        if (f.colorPath.empty()) continue;
        if (fs::is_regular_file(f.colorPath, ec)) {
            ++withColor;
            continue;
        }
        if (missingColor++ < kMaxFrameWarnings)
            ds->warnings_.push_back("colour image " + f.colorPath.string() + " (frame " + std::to_string(f.index) +
                                    ") does not exist; that frame has no colour");
        f.colorPath.clear();
    }
    if (missingColor > kMaxFrameWarnings)
        ds->warnings_.push_back("... and " + std::to_string(missingColor - kMaxFrameWarnings) + " more missing colour images");
    if (layout.framesWithoutColor > kMaxFrameWarnings)
        ds->warnings_.push_back("... and " + std::to_string(layout.framesWithoutColor - kMaxFrameWarnings) +
                                " more depth frames without a colour image");
    ds->hasColor_ = withColor > 0;
    if (!ds->hasColor_) ds->warnings_.push_back("no colour images: depth only");
    ds->frames_ = std::move(layout.frames);

    // The image size comes from frame 0; loadDepth holds every other frame to it.
    cv::Mat first = readRawDepth(ds->frames_.front().depthPath);
    k.width = first.cols;
    k.height = first.rows;
    const std::string firstName = ds->frames_.front().depthPath.string();
    // A calibration that states its image size must match the images: fusing 320x240 images with 640x480
    // intrinsics gives a plausible-looking but wrong mesh.
    if (camera && ((camera->width && *camera->width != k.width) || (camera->height && *camera->height != k.height)))
        throw Error(cameraJson.string() + ": calibration for " +
                    (camera->width ? std::to_string(*camera->width) : std::string("?")) + "x" +
                    (camera->height ? std::to_string(*camera->height) : std::string("?")) + " images, but depth image " +
                    firstName + " (frame 0) is " + std::to_string(k.width) + "x" + std::to_string(k.height));
    // Without a stated size, a principal point outside the image is the sign of the same mistake; only a
    // warning, since nothing says which of the two is wrong (and tiny test images use default intrinsics).
    if (k.cx < 0 || k.cx > k.width || k.cy < 0 || k.cy > k.height)
        ds->warnings_.push_back("principal point cx=" + fmt(k.cx) + " cy=" + fmt(k.cy) + " lies outside the " +
                                std::to_string(k.width) + "x" + std::to_string(k.height) + " depth images (" +
                                firstName + "): are the intrinsics for another image size?");
    ds->intrinsics_ = k;

    // A colour camera of its own (camera.json color_*): every depth pixel's ray, projected into it, gives the
    // remap that puts colour on the depth grid. The colour images' size is the file's, or frame 0's image.
    if (camera && camera->colorFx && ds->hasColor_) {
        Intrinsics ck{float(*camera->colorFx), float(*camera->colorFy), float(*camera->colorCx), float(*camera->colorCy),
                      camera->colorWidth.value_or(0), camera->colorHeight.value_or(0)};
        if (ck.width == 0 || ck.height == 0) {
            const auto withColor = std::find_if(ds->frames_.begin(), ds->frames_.end(),
                                                [](const FrameInfo& f) { return !f.colorPath.empty(); });
            try {
                std::ifstream in(withColor->colorPath, std::ios::binary);
                const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
                const ColorImage c = io::decodeColorImage(bytes, withColor->colorPath.string());
                if (ck.width == 0) ck.width = c.width;
                if (ck.height == 0) ck.height = c.height;
            } catch (const Error& e) {
                ds->warnings_.push_back(std::string(e.what()) + "; without color_width and color_height in " +
                                        cameraJson.string() + " the colour images' size is unknown: depth only");
                ds->hasColor_ = false;
            }
        }
        if (ds->hasColor_) {
            ds->colorIntrinsics_ = ck;
            ds->colorMapX_.resize(size_t(k.width) * k.height);
            ds->colorMapY_.resize(size_t(k.width) * k.height);
            for (int v = 0; v < k.height; ++v)
                for (int u = 0; u < k.width; ++u) {
                    const size_t i = size_t(v) * k.width + u;
                    ds->colorMapX_[i] = float(ck.fx * ((u - k.cx) / k.fx) + ck.cx);
                    ds->colorMapY_[i] = float(ck.fy * ((v - k.cy) / k.fy) + ck.cy);
                }
        }
    }
    return ds;
}

const FrameInfo& Dataset::frame(size_t i) const {
    if (i >= frames_.size())
        throw Error("frame " + std::to_string(i) + " out of range: the dataset " + folder_.string() + " has " +
                    std::to_string(frames_.size()) + " frames");
    return frames_[i];
}

DepthImage Dataset::loadDepth(size_t i) const {
    const FrameInfo& f = frame(i);
    cv::Mat raw = readRawDepth(f.depthPath);
    if (raw.cols != intrinsics_.width || raw.rows != intrinsics_.height)
        throw Error("depth image " + f.depthPath.string() + " is " + std::to_string(raw.cols) + "x" +
                    std::to_string(raw.rows) + " but frame 0 (" + frames_.front().depthPath.filename().string() +
                    ") is " + std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height));
    return io::rawDepthToMeters(raw, depthScale_, invalidRaw_, maxDepth_);
}

ColorImage Dataset::loadColor(size_t i, std::string* warning) const {
    const FrameInfo& f = frame(i);
    auto unusable = [&](const std::string& why) {
        if (warning) *warning = why + "; frame " + std::to_string(i) + " has no colour";
        return ColorImage{};
    };
    // A frame without an image is only worth a word when the sequence has colour elsewhere.
    if (f.colorPath.empty())
        return hasColor_ ? unusable("no colour image for depth image " + f.depthPath.filename().string()) : ColorImage{};
    const std::string name = f.colorPath.string();
    std::string bytes;
    {
        std::ifstream in(f.colorPath, std::ios::binary);
        if (!in) return unusable("cannot open colour image " + name);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (in.bad()) return unusable("error while reading colour image " + name);
    }
    ColorImage image;
    try {
        image = io::decodeColorImage(bytes, name);
    } catch (const Error& e) {
        return unusable(e.what());
    }
    const int w = colorIntrinsics_ ? colorIntrinsics_->width : intrinsics_.width;
    const int h = colorIntrinsics_ ? colorIntrinsics_->height : intrinsics_.height;
    if (image.width != w || image.height != h)
        return unusable("colour image " + name + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                        " but " + (colorIntrinsics_ ? "the colour calibration (camera.json) is for " : "the depth images are ") +
                        std::to_string(w) + "x" + std::to_string(h));
    if (!colorIntrinsics_) return image;

    // Bilinear resampling onto the depth grid; depth pixels outside the colour camera's view get black.
    const cv::Mat src(image.height, image.width, CV_8UC3, image.rgb.data());
    const cv::Mat mapX(intrinsics_.height, intrinsics_.width, CV_32FC1, const_cast<float*>(colorMapX_.data()));
    const cv::Mat mapY(intrinsics_.height, intrinsics_.width, CV_32FC1, const_cast<float*>(colorMapY_.data()));
    ColorImage out;
    out.width = intrinsics_.width;
    out.height = intrinsics_.height;
    out.rgb.resize(size_t(out.width) * out.height * 3);
    cv::Mat dst(out.height, out.width, CV_8UC3, out.rgb.data());  // remap writes into out.rgb directly
    try {
        cv::remap(src, dst, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
    } catch (const cv::Exception& e) {
        return unusable("cannot resample colour image " + name + ": " + e.what());
    }
    return out;
}

}  // namespace vkmesh
