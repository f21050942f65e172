// What the layout readers share (layout_reader.h), and the calibration functions of io/dataset.h: camera
// presets, --intrinsics, the intrinsics check.
#include "io/data_dir.h"
#include "io/datasets/layout_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <utility>

namespace vkmesh {

namespace datasets {

using namespace io::text;

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

void summariseFramesWithoutPose(Layout& layout, const std::string& why) {
    // A sequence with no poses at all needs no warning (the caller asked for it and sees hasPoses());
    // a gap inside a trajectory is worth one line, since those frames' poses will be estimated.
    const size_t without = size_t(std::count_if(layout.frames.begin(), layout.frames.end(),
                                                [](const FrameInfo& f) { return !f.hasPose; }));
    if (without > 0 && without < layout.frames.size())
        layout.warnings.push_back(std::to_string(without) + " of " + std::to_string(layout.frames.size()) +
                                  " depth frames have " + why + "; kept without a pose (" + kTrackingHint + ")");
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

std::vector<fs::path> filesWithExtension(const fs::path& dir, const std::string& ext) {
    std::vector<fs::path> out;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.is_regular_file(ec) && lower(e.path().extension().string()) == ext) out.push_back(e.path());
    std::sort(out.begin(), out.end(),
              [](const fs::path& a, const fs::path& b) { return naturalLess(a.filename().string(), b.filename().string()); });
    return out;
}

std::vector<fs::path> colorImagesIn(const fs::path& dir) {
    std::vector<fs::path> colors;
    for (const char* ext : {".jpg", ".jpeg", ".png"})
        for (fs::path& p : filesWithExtension(dir, ext)) colors.push_back(std::move(p));
    std::sort(colors.begin(), colors.end(),
              [](const fs::path& a, const fs::path& b) { return naturalLess(a.filename().string(), b.filename().string()); });
    return colors;
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

io::CameraJson readCameraJson(const fs::path& file) {
    std::ifstream in = openText(file);
    return io::parseCameraJson(in, file.string());
}

}  // namespace datasets

using namespace io::text;

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

}  // namespace vkmesh
