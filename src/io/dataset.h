// Depth-sequence input: a user hands vkmesh a folder, Dataset::open recognises its layout and yields
// depth frames in metres with camera-to-world poses and pinhole intrinsics.
//
// Layouts (detected in this order):
//   TUM RGB-D     depth.txt (or, without it, associations.txt) + groundtruth.txt; depth PNG uint16 / 5000.
//   ICL-NUIM      the same files in the TUM-compatible release; recognised by "icl" in the folder name or by
//                 timestamps that are small integers (frame indices). fy is negative (-480) with its poses.
//   Redwood       a *.log trajectory (Zhou-Koltun format) + depth/*.png in millimetres.
//   7-Scenes      frame-NNNNNN.depth.png (mm, 0 and 65535 invalid) + frame-NNNNNN.pose.txt.
// Any layout may carry a camera.json ({"fx","fy","cx","cy","depth_scale"}, all optional; colour intrinsics
// "color_fx","color_fy","color_cx","color_cy" and "color_width","color_height" when the colour camera differs).
//
// Colour (optional, per frame; FrameInfo::colorPath, loadColor):
//   TUM, ICL-NUIM rgb.txt ("timestamp path"): the image nearest in time to the depth frame, within 20 ms (TUM)
//                 or with the same frame index (ICL-NUIM).
//   Redwood       color/ or rgb/ beside depth/: the k-th image (name order) goes with the k-th depth image.
//   7-Scenes      frame-NNNNNN.color.png or frame-NNNNNN.color.jpg beside the depth image.
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

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vkmesh {

enum class DatasetKind { TUM, ICLNUIM, Redwood, SevenScenes };
std::string toString(DatasetKind kind);

struct DatasetOptions {
    std::optional<Intrinsics> intrinsics;  // --intrinsics fx,fy,cx,cy override (width/height come from the images)
    std::optional<double> depthScale;      // --depth-scale: raw uint16 units per metre (5000 TUM, 1000 mm)
    float maxDepth = 0;                    // --max-depth in metres; 0 = no limit; deeper samples become 0
    size_t maxFrames = 0;                  // --frames N: keep the first N frames that have a pose; 0 = all
};

struct FrameInfo {
    size_t index = 0;          // position in the Dataset (frame(i).index == i)
    double timestamp = 0;      // seconds (TUM), frame index (ICL-NUIM), frame number (Redwood, 7-Scenes)
    std::filesystem::path depthPath;  // absolute or relative to the working directory, ready to open
    std::filesystem::path colorPath;  // the frame's colour image, as depthPath; empty when it has none
    Pose cameraToWorld = Pose::Identity();
};

class Dataset {
public:
    // Detects the layout of `folder`, reads its index and trajectory files, associates depth frames with
    // poses and reads frame 0's PNG for the image size. Throws vkmesh::Error (naming the file, line or
    // value at fault) on anything it cannot use; frames without a pose are skipped and reported in
    // warnings() instead, unless no frame has one.
    static std::unique_ptr<Dataset> open(const std::filesystem::path& folder, const DatasetOptions& options = {});

    DatasetKind kind() const { return kind_; }
    const std::filesystem::path& folder() const { return folder_; }
    const Intrinsics& intrinsics() const { return intrinsics_; }
    double depthScale() const { return depthScale_; }
    float maxDepth() const { return maxDepth_; }

    size_t size() const { return frames_.size(); }
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
    ColorImage loadColor(size_t i, std::string* warning = nullptr) const;

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
    // Colour camera calibration from camera.json, when it differs from the depth camera's.
    std::optional<Intrinsics> colorIntrinsics_;
    // With colorIntrinsics_: for every depth pixel, where it lies in the colour image (x, y; cv::remap maps).
    std::vector<float> colorMapX_, colorMapY_;
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

// Checks that `pose` is a rigid camera-to-world transform: finite, rotation orthonormal within 1e-3
// (max |R^T R - I|), determinant +1 (not a reflection), bottom row 0 0 0 1. Throws Error starting with
// `where` (a file and line, or a frame) otherwise.
void validatePose(const Pose& pose, const std::string& where);

}  // namespace vkmesh
