// Internal to Dataset::open (src/io/dataset.cpp): one reader per dataset layout, each in its own file in this
// folder, and what they share. A reader lists a sequence's depth frames with their poses (where it has them)
// and colour images, and says which calibration preset fits; Dataset::open detects the layout, calls its
// reader, then applies the steps common to all layouts (calibration precedence, maxFrames, frame 0's size,
// colour registration).
#pragma once

#include "io/color_registration.h"
#include "io/dataset.h"
#include "io/parsers.h"
#include "io/text_lines.h"

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vkmesh::datasets {

namespace fs = std::filesystem;

class RecordingSource;

// Said wherever poses are missing: such a sequence is still usable, with camera tracking.
inline const std::string kTrackingHint = "vkmesh fuse --track estimates them";

// What a layout reader hands back to Dataset::open before the common steps (calibration overrides,
// maxFrames, reading frame 0).
struct Layout {
    DatasetKind kind = DatasetKind::TUM;
    // The layout's default calibration: a camera preset (data/cameras/<name>/camera.json), read by
    // Dataset::open only when the folder's camera.json and the options leave a value to it. Empty for a
    // layout that has no default (Folder): then camera.json or the options must give every value.
    std::string preset;
    std::optional<Intrinsics> folderIntrinsics;  // the sequence's own calibration file (7-Scenes)
    std::string intrinsicsWarning;  // set when the default is a guess rather than the sequence's calibration
    std::optional<uint16_t> invalidRaw;
    std::vector<FrameInfo> frames;  // in time order; with a pose unless the options allow frames without one
    std::vector<std::string> warnings;
    size_t skipped = 0;
    size_t framesWithoutColor = 0;  // in a layout that has colour

    // Recordings (recording_source.h): where the frames' bytes are, and what the recording says of its cameras.
    std::shared_ptr<const RecordingSource> recording;
    std::optional<double> ownDepthScale;  // the recording's depth unit (raw units per metre)
    std::optional<ColorCamera> colorCamera;  // a colour camera of its own: intrinsics and, when known, extrinsics
    std::string description;  // "ROS 1 bag, depth /camera/depth/image (32FC1), colour /camera/rgb/image_color"
};

// Per-frame warnings are capped so that a sequence with a long tracking gap does not flood the log.
constexpr size_t kMaxFrameWarnings = 20;

// A depth frame that gets no colour image (it is fused without colour); capped like skipped frames.
void warnNoColor(Layout& layout, const std::string& message);
void warnSkipped(Layout& layout, const std::string& message);
void summariseSkipped(Layout& layout, size_t listed, const std::string& why);
// One warning when some frames but not all got a pose from `source` (kept without one for tracking).
void summariseFramesWithoutPose(Layout& layout, const std::string& why);

// True if `word` occurs in `name` not preceded by a letter and not followed by a digit.
bool containsWord(const std::string& name, const std::string& word);
// Orders file names as a person would ("2.png" before "10.png").
bool naturalLess(const std::string& a, const std::string& b);
// The regular files in `dir` whose extension is `ext` (lower case, with the dot; matched case-insensitively),
// in natural name order; none when `dir` does not exist.
std::vector<fs::path> filesWithExtension(const fs::path& dir, const std::string& ext);
// The colour images (.jpg, .jpeg, .png) in `dir`, in natural name order.
std::vector<fs::path> colorImagesIn(const fs::path& dir);

// Reads a depth PNG as raw uint16 samples. Everything that can go wrong is reported with the file's name.
cv::Mat readRawDepth(const fs::path& file);
io::CameraJson readCameraJson(const fs::path& file);

// --- the readers; each throws Error naming the file or folder at fault ---

// TUM RGB-D and ICL-NUIM (TUM-compatible release): depth.txt or associations.txt, groundtruth.txt, rgb.txt.
Layout readTum(const fs::path& folder, const std::string& folderName, bool requirePoses);

// Redwood / Zhou-Koltun: depth/*.png (millimetres) and the *.log trajectory, when there is one.
Layout readRedwood(const fs::path& folder, const std::optional<fs::path>& logFile, bool requirePoses);

// 7-Scenes: frame-NNNNNN.depth.png + frame-NNNNNN.pose.txt (millimetres, 0 and 65535 invalid).
struct SevenScenesFrame {
    long long number;
    fs::path depth;
};
std::vector<SevenScenesFrame> listSevenScenesFrames(const fs::path& dir);
Layout readSevenScenes(const fs::path& folder, const std::vector<SevenScenesFrame>& images, bool requirePoses);

// A plain folder of depth (+ colour) images with a camera.json; never has poses.
// Where its depth images are: depth/ when the folder has one, else the folder itself.
fs::path folderLayoutDepthDir(const fs::path& folder);
Layout readFolder(const fs::path& folder, bool requirePoses);

}  // namespace vkmesh::datasets
