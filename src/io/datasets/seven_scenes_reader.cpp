// 7-Scenes: frame-NNNNNN.depth.png + frame-NNNNNN.pose.txt (millimetres, 0 and 65535 invalid), colour in
// frame-NNNNNN.color.png/.jpg, calibration in camera-intrinsics.txt beside the frames or in the scene folder.
#include "io/datasets/layout_reader.h"

#include <algorithm>
#include <cmath>

namespace vkmesh::datasets {

using namespace io::text;

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

namespace {

std::vector<double> readNumbers(const fs::path& file, size_t count, const std::string& what) {
    std::ifstream in = openText(file);
    return io::parseNumbers(in, file.string(), count, what);
}

}  // namespace

Layout readSevenScenes(const fs::path& folder, const std::vector<SevenScenesFrame>& images, bool requirePoses) {
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
        FrameInfo f;
        f.timestamp = static_cast<double>(img.number);
        f.depthPath = img.depth;
        if (fs::is_regular_file(poseFile, ec)) {
            std::vector<double> m = readNumbers(poseFile, 16, "a 4x4 camera-to-world matrix");
            Pose T;
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) T(r, c) = m[r * 4 + c];
            validatePose(T, poseFile.string() + " (frame " + std::to_string(img.number) + ")");
            f.cameraToWorld = T;
            f.hasPose = true;
        } else if (requirePoses) {
            warnSkipped(layout, img.depth.filename().string() + ": no " + poseFile.filename().string() + "; skipped");
            continue;
        }
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
                    " has a matching frame-*.pose.txt with the camera pose (" + kTrackingHint + ")");
    summariseSkipped(layout, images.size(), "no pose file");
    summariseFramesWithoutPose(layout, "no frame-NNNNNN.pose.txt");
    return layout;
}

}  // namespace vkmesh::datasets
