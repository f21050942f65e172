// Depth-sequence input: a user hands vkmesh a folder, Dataset::open recognises its layout and yields
// depth frames in metres with camera-to-world poses and pinhole intrinsics.
//
// Layouts (detected in this order):
//   TUM RGB-D     depth.txt (or, without it, associations.txt) + groundtruth.txt; depth PNG uint16 / 5000.
//   ICL-NUIM      the same files in the TUM-compatible release; recognised by "icl" in the folder name or by
//                 timestamps that are small integers (frame indices). fy is negative (-480) with its poses.
//   Redwood       a *.log trajectory (Zhou-Koltun format) + depth/*.png in millimetres.
//   7-Scenes      frame-NNNNNN.depth.png (mm, 0 and 65535 invalid) + frame-NNNNNN.pose.txt.
//   Folder        a plain folder of depth images with a camera.json and no poses (a RealSense recording, a
//                 phone scan): *.png 16-bit in depth/ (or in the folder itself when it has no depth/), in
//                 name order with numbers compared as numbers; camera.json must give fx, fy, cx, cy and
//                 depth_scale (there is no default to fall back on). Detected last.
// Sequences without poses (TUM/ICL-NUIM without groundtruth.txt, Redwood without its *.log, 7-Scenes
// without frame-*.pose.txt, any Folder) open only with DatasetOptions::requirePoses = false, for camera
// tracking to estimate the poses; a depth/ folder with neither a *.log nor a camera.json is then read as
// Redwood (its default calibration, with a warning).
// Any layout may carry a camera.json ({"fx","fy","cx","cy","depth_scale"}, all optional; colour intrinsics
// "color_fx","color_fy","color_cx","color_cy" and "color_width","color_height" when the colour camera differs).
//
// Colour (optional, per frame; FrameInfo::colorPath, loadColor):
//   TUM, ICL-NUIM rgb.txt ("timestamp path"): the image nearest in time to the depth frame, within 20 ms (TUM)
//                 or with the same frame index (ICL-NUIM).
//   Redwood       color/ or rgb/ beside depth/: the k-th image (name order) goes with the k-th depth image.
//   7-Scenes      frame-NNNNNN.color.png or frame-NNNNNN.color.jpg beside the depth image.
//   Folder        color/ or rgb/: the image with the depth image's name stem, else (no stem matches and the
//                 counts are equal) the k-th image in name order.
// JPEG or PNG, 8-bit: 3-channel (BGR in the file as OpenCV decodes it, RGB in ColorImage), 4-channel (alpha
// dropped) or grayscale (grey RGB). 16-bit images are rejected (usually a depth image listed by mistake).
// Colour is registered to the depth grid: without colour intrinsics the images must be the depth images'
// size and are taken pixel for pixel; with them, each depth pixel's ray is projected into the colour camera
// (no baseline between the two) and the colour image resampled bilinearly there.
// Precedence of calibration values: DatasetOptions > camera.json > the layout's default.
// The layouts' defaults are camera presets in vkmesh's data folder (data/cameras/<name>/camera.json, the
// same format; found as io/data_dir.h says): tum_fr1, tum_fr2, tum_fr3 (chosen by freiburgN / frN in the
// folder name), tum_default (a TUM folder that names no sensor), icl_nuim, redwood, seven_scenes. A preset
// is read only when the folder and the options leave a value to it: a fully calibrated folder needs no data.
// Part of the vkmesh_io library (OpenCV reads the PNGs).
#pragma once

#include "core/types.h"
#include "io/trajectory.h"  // validatePose, the check every pose read here passes

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vkmesh {

namespace datasets {
class RecordingSource;  // io/datasets/recording_source.h
}

// The recordings (a file, or a rosbag2 folder; docs/RECORDINGS.md): RosBag a ROS 1 bag 2.0, RealSenseBag one in
// librealsense's layout, Mcap an MCAP file, Rosbag2 a rosbag2 SQLite .db3 (or a rosbag2 folder).
enum class DatasetKind { TUM, ICLNUIM, Redwood, SevenScenes, Folder, RosBag, RealSenseBag, Mcap, Rosbag2 };
std::string toString(DatasetKind kind);

struct DatasetOptions {
    std::optional<Intrinsics> intrinsics;  // --intrinsics fx,fy,cx,cy override (width/height come from the images)
    std::optional<double> depthScale;      // --depth-scale: raw uint16 units per metre (5000 TUM, 1000 mm)
    float maxDepth = 0;                    // --max-depth in metres; 0 = no limit; deeper samples become 0
    size_t maxFrames = 0;                  // --frames N: keep the first N frames that have a pose (every
                                           // listed frame without requirePoses); 0 = all
    // false when camera tracking will estimate the poses (vkmesh fuse --track): a sequence without pose files
    // opens, and a listed depth frame with no pose near enough is kept (FrameInfo::hasPose false) instead of
    // skipped. true: a sequence without poses is an error saying that --track exists.
    bool requirePoses = true;
    // Recordings: the topics to read when the type alone does not tell (--depth-topic, --color-topic,
    // --info-topic: the depth camera's sensor_msgs/CameraInfo). Empty: chosen by message type and name.
    std::string depthTopic, colorTopic, infoTopic;
};

struct FrameInfo {
    size_t index = 0;          // position in the Dataset (frame(i).index == i)
    // Seconds (TUM), frame index (ICL-NUIM), frame number (7-Scenes: from the name; Redwood: the image's
    // position in name order, which is what its .log's ids count); Folder: the number in the file name (the
    // whole stem when it is a number, else its last run of digits), or the frame's position in name order
    // when a name has none or the numbers do not increase in name order.
    double timestamp = 0;
    std::filesystem::path depthPath;  // absolute or relative to the working directory, ready to open
    std::filesystem::path colorPath;  // the frame's colour image, as depthPath; empty when it has none
    Pose cameraToWorld = Pose::Identity();  // the dataset's pose when hasPose, identity otherwise
    bool hasPose = false;                   // whether the dataset gave this frame's pose
    // Recordings: depthPath and colorPath are the recording; these say which message ("message 12 on
    // /camera/depth/image (chunk at byte 4096)"). Empty for image files.
    std::string depthRecord, colorRecord;
};

class Dataset {
public:
    // Detects the layout of `folder`, reads its index and trajectory files, associates depth frames with
    // poses and reads frame 0's PNG for the image size. Throws vkmesh::Error (naming the file, line or
    // value at fault) on anything it cannot use; frames without a pose are skipped and reported in
    // warnings() instead, unless no frame has one; with options.requirePoses false they are kept without one.
    // `folder` may also be a recording (a .bag, .mcap or .db3 file, or a rosbag2 folder; detected by content).
    static std::unique_ptr<Dataset> open(const std::filesystem::path& folder, const DatasetOptions& options = {});

    DatasetKind kind() const { return kind_; }
    const std::filesystem::path& folder() const { return folder_; }
    // Recordings: the container and the topics read ("ROS 1 bag, depth /camera/depth/image (32FC1), colour ...");
    // empty for image folders.
    const std::string& description() const { return description_; }
    const Intrinsics& intrinsics() const { return intrinsics_; }
    double depthScale() const { return depthScale_; }
    float maxDepth() const { return maxDepth_; }

    size_t size() const { return frames_.size(); }
    // Whether any frame has a pose from the dataset (always, when opened with requirePoses).
    bool hasPoses() const { return hasPoses_; }
    const FrameInfo& frame(size_t i) const;

    // Human-readable notes from open(): skipped frames and why, fallbacks to default intrinsics, duplicates.
    const std::vector<std::string>& warnings() const { return warnings_; }
    // How many listed depth frames open() dropped: no pose near enough, or a duplicated timestamp.
    size_t skippedFrames() const { return skippedFrames_; }

    // Reads frame i's depth in metres (0 = invalid; samples beyond maxDepth are set to 0). An all-zero image
    // is returned as is. Const and stateless, so frames may be loaded from several threads at once. Throws vkmesh::Error naming the file if it is missing, unreadable, not a 16-bit
    // single-channel image, or not the size of frame 0.
    DepthImage loadDepth(size_t i) const;

    // Whether at least one frame has a colour image (open() checked that the file exists).
    bool hasColor() const { return hasColor_; }

    // Frame i's colour registered to the depth image grid (intrinsics().width x height, RGB8). Returns an
    // empty image when the frame has none, or when its file is missing, unreadable, corrupt, 16-bit, or of
    // another size than expected; then *warning (when given) names the file and the problem (it is left
    // untouched otherwise). Never throws for a bad image; only for i out of range. Const and stateless, like
    // loadDepth.
    // With a colour camera beside the depth camera (extrinsics in camera.json's depth_to_color or in a recording),
    // colour is registered through each pixel's depth (io/color_registration.h): pass frame i's depth when it is
    // already loaded, or it is loaded here.
    ColorImage loadColor(size_t i, std::string* warning = nullptr, const DepthImage* depth = nullptr) const;

private:
    Dataset() = default;

    DatasetKind kind_ = DatasetKind::TUM;
    std::filesystem::path folder_;
    Intrinsics intrinsics_;
    double depthScale_ = 5000.0;
    float maxDepth_ = 0;
    std::optional<uint16_t> invalidRaw_;  // a raw value that also means "no measurement" (7-Scenes: 65535)
    std::vector<FrameInfo> frames_;
    std::vector<std::string> warnings_;
    size_t skippedFrames_ = 0;
    bool hasColor_ = false;
    bool hasPoses_ = false;
    // Colour camera calibration from camera.json, when it differs from the depth camera's.
    std::optional<Intrinsics> colorIntrinsics_;
    // With colorIntrinsics_: for every depth pixel, where it lies in the colour image (x, y; cv::remap maps).
    std::vector<float> colorMapX_, colorMapY_;
    // A colour camera with a baseline (extrinsics known): registered through depth instead of by the maps above.
    std::optional<Eigen::Matrix4d> depthToColor_;
    std::shared_ptr<const datasets::RecordingSource> recording_;
    std::string description_;
};

// A camera preset: data/cameras/<name>/camera.json with all of fx, fy, cx, cy and depth_scale.
struct CameraPreset {
    std::string name;
    std::filesystem::path file;  // where it was read
    Intrinsics intrinsics;       // width/height 0 unless the file states them
    double depthScale = 0;       // raw units per metre
};
// Reads preset `name`. Throws Error naming the missing file and the folders searched (io/data_dir.h), or the
// file and the value at fault when it is incomplete or invalid.
CameraPreset loadCameraPreset(const std::string& name);

// Parses "fx,fy,cx,cy" (as given to --intrinsics); width and height stay 0. Throws Error naming the bad
// value: not four numbers, a non-number, non-finite values, or fx/fy equal to 0.
Intrinsics parseIntrinsics(const std::string& text);

// Checks a camera's fx, fy, cx, cy: finite, fx > 0, fy non-zero (negative only with ICL-NUIM's poses, which
// Dataset::open checks against the layout). Throws Error starting with `source` and naming the bad value.
void checkIntrinsics(const Intrinsics& intrinsics, const std::string& source);

}  // namespace vkmesh
