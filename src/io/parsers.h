// The parsers behind Dataset::open, on in-memory text and bytes rather than on files in a folder, so that
// the fuzz targets (fuzz/) and the hostile-input tests can drive each one directly. Dataset::open opens the
// files and calls these; the behaviour and the messages are the same either way.
//
// Every function throws vkmesh::Error whose message starts with `source` (the file's path as given, with
// ":line" where a line is at fault) and names the offending value. Nothing else may escape: any other
// exception, crash or sanitizer report on any input is a bug (the fuzzers check exactly that).
#pragma once

#include "core/types.h"
#include "io/trajectory.h"  // io::parseTrajectory and io::TimedPose, TUM's trajectory format (vkmesh_base)

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vkmesh::io {

struct TimedPath {
    double timestamp;
    size_t line;
    std::filesystem::path path;  // folder / the listed relative path
};

struct IndexedPose {
    long long id;  // the first id of a Redwood block header: the depth image's 0-based index
    size_t line;   // line of the block header
    Pose cameraToWorld;
};

// TUM groundtruth.txt and ICL-NUIM's *.gt.freiburg: io::parseTrajectory in io/trajectory.h, shared with
// readTumTrajectory (the trajectories vkmesh writes).

// TUM depth.txt: "timestamp path" per line.
std::vector<TimedPath> parseDepthList(std::istream& in, const std::string& source, const std::filesystem::path& folder);

// associations.txt: "timestamp path" pairs side by side; the depth pair is the one whose path names "depth".
std::vector<TimedPath> parseAssociations(std::istream& in, const std::string& source,
                                         const std::filesystem::path& folder);

// Redwood / Zhou-Koltun *.log: blocks of "id id frame" + a 4x4 camera-to-world matrix, each validated.
std::vector<IndexedPose> parseRedwoodLog(std::istream& in, const std::string& source);

// All the numbers of a small text file, which must hold exactly `count` of them (a 7-Scenes 4x4 pose, a
// 3x3 camera matrix); `what` names the expected content for the message.
std::vector<double> parseNumbers(std::istream& in, const std::string& source, size_t count, const std::string& what);

// camera.json: {"fx","fy","cx","cy","depth_scale","width","height"} and the colour camera's "color_fx",
// "color_fy","color_cx","color_cy" (all four or none; fx, fy positive), "color_width","color_height"; every
// key optional but at least one of the calibration keys present. Unknown keys are returned in `ignoredKeys` (the caller warns).
struct CameraJson {
    std::optional<double> fx, fy, cx, cy, depthScale;
    std::optional<int> width, height;  // the image size the calibration is for, when the file says
    // The colour camera's, when it differs from the depth camera's: all four or none (else Error).
    std::optional<double> colorFx, colorFy, colorCx, colorCy;
    std::optional<int> colorWidth, colorHeight;
    // "depth_to_color": {"rotation": [9 numbers, row-major], "translation": [x, y, z] metres}: p_color = R p_depth + t,
    // the colour camera's pose relative to the depth camera's (a baseline): colour is then registered through depth.
    std::optional<Eigen::Matrix4d> depthToColor;
    std::vector<std::string> ignoredKeys;
    bool hasAllIntrinsics() const { return fx && fy && cx && cy; }
};
CameraJson parseCameraJson(std::istream& in, const std::string& source);

// Largest depth image accepted, checked on the PNG header before decoding so that a corrupt or hostile
// header cannot make the decoder allocate gigabytes: 16384 per side and 64 Mpixel in all, 30 times the
// largest depth sensor vkmesh knows of.
constexpr uint32_t kMaxDepthImageSide = 16384;
constexpr uint64_t kMaxDepthImagePixels = uint64_t(1) << 26;

// Decodes a depth PNG held in memory into raw uint16 samples (CV_16UC1). Throws Error naming `source` if
// the bytes are not a PNG, the header is not 16-bit single-channel (grayscale), the image is empty or
// larger than the limits above, or the data is corrupt or truncated.
cv::Mat decodeDepthPng(std::string_view bytes, const std::string& source);

// Raw samples to metres: 0 and `invalidRaw` mean "no measurement"; samples beyond maxDepth (> 0) become 0.
DepthImage rawDepthToMeters(const cv::Mat& raw, double depthScale, std::optional<uint16_t> invalidRaw, float maxDepth);
// The same on samples in memory, rows `rowStride` samples apart, into `out` (whose buffer is reused): the one
// conversion for a dataset's PNGs and an application's arrays (the Python module), so both give the same floats.
void rawDepthToMeters(const uint16_t* raw, int width, int height, size_t rowStride, double depthScale,
                      std::optional<uint16_t> invalidRaw, float maxDepth, DepthImage& out);

}  // namespace vkmesh::io

namespace vkmesh::io {

// Decodes a colour image (PNG or JPEG) held in memory into RGB8. 8-bit 3-channel images are taken as BGR (as
// OpenCV decodes them), 4-channel ones lose their alpha, grayscale ones become grey RGB. Throws Error naming
// `source` for bytes that are not a PNG or JPEG, a header claiming more than the depth limits above, a
// 16-bit image, or corrupt / truncated data.
ColorImage decodeColorImage(std::string_view bytes, const std::string& source);

}  // namespace vkmesh::io
