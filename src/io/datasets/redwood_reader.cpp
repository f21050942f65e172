// Redwood / Zhou-Koltun: depth/*.png in millimetres and a *.log trajectory; colour in color/ or rgb/.
#include "io/datasets/layout_reader.h"

#include <map>
#include <utility>

namespace vkmesh::datasets {

using namespace io::text;

namespace {

// The *.log: blocks of five lines, "id id frame" then the camera-to-world matrix. The first id is the
// 0-based index of the depth image (in name order) the pose belongs to. Returns id -> pose.
std::map<long long, Pose> readRedwoodPoses(const fs::path& logFile, bool requirePoses, Layout& layout) {
    std::ifstream logIn = openText(logFile);
    std::map<long long, Pose> poses;
    size_t duplicates = 0;
    for (const io::IndexedPose& p : io::parseRedwoodLog(logIn, logFile.string())) {
        if (!poses.emplace(p.id, p.cameraToWorld).second) {
            if (duplicates++ < kMaxFrameWarnings)
                layout.warnings.push_back(at(logFile, p.line) + ": frame " + std::to_string(p.id) +
                                          " appears again; kept the first pose");
        }
    }
    if (poses.empty() && requirePoses) throw Error(logFile.string() + " has no poses (" + kTrackingHint + ")");
    return poses;
}

}  // namespace

Layout readRedwood(const fs::path& folder, const std::optional<fs::path>& logFile, bool requirePoses) {
    Layout layout;
    layout.kind = DatasetKind::Redwood;
    layout.preset = "redwood";  // PrimeSense defaults, depth in millimetres
    if (!logFile && requirePoses)
        throw Error("Redwood layout in " + folder.string() + ": found depth/ but no *.log trajectory with the camera poses (" +
                    kTrackingHint + ")");

    std::vector<fs::path> images = filesWithExtension(folder / "depth", ".png");
    if (images.empty()) throw Error("Redwood layout: " + (folder / "depth").string() + " holds no .png depth images");

    std::map<long long, Pose> poses;
    if (logFile) {
        poses = readRedwoodPoses(*logFile, requirePoses, layout);
    } else {
        // Only a depth/ folder says this is Redwood: its calibration is a guess (Dataset::open appends the values).
        layout.intrinsicsWarning = "no *.log trajectory and no camera.json in " + folder.string() +
                                   ": read as a Redwood sequence (depth/ in millimetres) with Redwood's default intrinsics";
    }
    const std::string logName = logFile ? logFile->filename().string() : std::string();

    for (size_t k = 0; k < images.size(); ++k) {
        FrameInfo f;
        f.timestamp = static_cast<double>(k);  // the position in name order, which the log's ids count
        f.depthPath = images[k];
        auto it = poses.find(static_cast<long long>(k));
        if (it != poses.end()) {
            f.cameraToWorld = it->second;
            f.hasPose = true;
        } else if (requirePoses) {
            warnSkipped(layout, (fs::path("depth") / images[k].filename()).string() + ": frame " + std::to_string(k) +
                                    " has no pose in " + logName + "; skipped");
            continue;
        }
        layout.frames.push_back(std::move(f));
    }
    size_t orphans = 0;
    for (const auto& [id, p] : poses)
        if (id < 0 || static_cast<size_t>(id) >= images.size()) ++orphans;
    if (orphans > 0)
        layout.warnings.push_back(std::to_string(orphans) + " poses in " + logName + " name frames beyond the " +
                                  std::to_string(images.size()) + " images in depth/; ignored");
    if (layout.frames.empty())
        throw Error("none of the " + std::to_string(images.size()) + " images in " + (folder / "depth").string() +
                    " has a pose in " + logFile->string() + " (frame ids " + std::to_string(poses.begin()->first) +
                    " .. " + std::to_string(poses.rbegin()->first) + ")");
    summariseSkipped(layout, images.size(), "no pose in " + logName);
    if (logFile) summariseFramesWithoutPose(layout, "no pose in " + logName);

    // Colour: color/ (Redwood) or rgb/ (some converters) beside depth/, paired by position in name order.
    for (const char* name : {"color", "rgb"}) {
        const std::vector<fs::path> colors = colorImagesIn(folder / name);
        if (colors.empty()) continue;
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

}  // namespace vkmesh::datasets
