// The parsers of the datasets' index and calibration text files (io/parsers.h): depth.txt, associations.txt,
// Redwood's *.log, 7-Scenes' 4x4 and 3x3 matrices, camera.json. They work on streams so that the fuzz
// targets and the hostile-input tests drive them directly; the layout readers open the files and call them.
// (TUM's groundtruth.txt is io::parseTrajectory, in io/trajectory.cpp.)
#include "io/parsers.h"
#include "io/text_lines.h"

#include <Eigen/LU>  // determinant() of depth_to_color's rotation

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>

namespace vkmesh::io {

namespace fs = std::filesystem;
using namespace text;

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
    if (auto it = j.find("depth_to_color"); it != j.end()) {
        const char* expected = "; expected {\"rotation\": [9 numbers, row-major], \"translation\": [x, y, z] in metres}";
        if (!it->is_object()) throw Error(source + ": \"depth_to_color\" is " + quote(*it) + expected);
        auto numbers = [&](const char* key, size_t n) {
            auto v = it->find(key);
            if (v == it->end() || !v->is_array() || v->size() != n ||
                !std::all_of(v->begin(), v->end(), [](const nlohmann::json& x) { return x.is_number() && std::isfinite(x.get<double>()); }))
                throw Error(source + ": \"depth_to_color\" \"" + key + "\" is " + (v == it->end() ? std::string("missing") : quote(*v)) + expected);
            std::vector<double> out;
            for (const auto& x : *v) out.push_back(x.get<double>());
            return out;
        };
        const std::vector<double> r = numbers("rotation", 9), t = numbers("translation", 3);
        Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
        for (int row = 0; row < 3; ++row) {
            for (int col = 0; col < 3; ++col) T(row, col) = r[size_t(row) * 3 + col];
            T(row, 3) = t[size_t(row)];
        }
        const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
        if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() < 0)
            throw Error(source + ": \"depth_to_color\" \"rotation\" is not a rotation (orthonormal, determinant +1)");
        c.depthToColor = T;
    }
    static const char* known[] = {"fx",       "fy",       "cx",       "cy",          "depth_scale",  "width", "height",
                                  "color_fx", "color_fy", "color_cx", "color_cy", "color_width", "color_height",
                                  "depth_to_color"};
    for (const auto& item : j.items())
        if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return item.key() == k; }) ==
            std::end(known))
            c.ignoredKeys.push_back(quote(item.key()));
    // A file with none of the keys (another tool's format, e.g. Open3D's "intrinsic_matrix", or every key
    // misspelt) would otherwise be ignored in silence and the layout's default calibration used.
    const bool anyColor = c.colorFx || c.colorFy || c.colorCx || c.colorCy || c.colorWidth || c.colorHeight || c.depthToColor;
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

}  // namespace vkmesh::io
