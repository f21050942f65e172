// Camera trajectories in the TUM RGB-D format ("timestamp tx ty tz qx qy qz qw" per line, camera-to-world,
// '#' comment lines): what `vkmesh fuse --trajectory` writes and what TUM's groundtruth.txt and ICL-NUIM's
// *.gt.freiburg hold, so that TUM's evaluation tools (evaluate_ate.py, evaluate_rpe.py) read vkmesh's poses
// and vkmesh reads theirs. Part of vkmesh_base (no OpenCV): an embedding application can write the poses
// it tracked without the dataset library.
#pragma once

#include "core/types.h"

#include <cstddef>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

namespace vkmesh {

struct TimedPose {
    double timestamp;    // seconds (TUM), or a frame number where the sequence has no clock
    Pose cameraToWorld;
};

// Writes `poses` in order, after the header comment "# timestamp tx ty tz qx qy qz qw". A timestamp that is
// an integer is written as one (a frame number), any other with 6 decimals (microseconds, as TUM's files);
// positions and the unit quaternion (qw >= 0) with 9 decimals. Throws Error naming the file when it cannot be
// written, or naming the entry when a timestamp is not finite or a pose is not rigid (validatePose).
void writeTumTrajectory(const std::filesystem::path& file, const std::vector<TimedPose>& poses);

// Reads a TUM trajectory file: every non-comment line "timestamp tx ty tz qx qy qz qw", in file order.
// Throws Error naming the file and line of a malformed line, a non-finite value, a quaternion far from unit
// norm or a non-rigid pose (the rules of io::parseTrajectory).
std::vector<TimedPose> readTumTrajectory(const std::filesystem::path& file);

// Checks that `pose` is a rigid camera-to-world transform: finite, rotation orthonormal within 1e-3
// (max |R^T R - I|), determinant +1 (not a reflection), bottom row 0 0 0 1. Throws Error starting with
// `where` (a file and line, or a frame) otherwise.
void validatePose(const Pose& pose, const std::string& where);

namespace io {

// A trajectory pose with the line it was read from, for messages that name file:line.
struct TimedPose : vkmesh::TimedPose {
    size_t line;  // 1-based line in the source
};

// TUM groundtruth.txt and ICL-NUIM's *.gt.freiburg: "timestamp tx ty tz qx qy qz qw" per line, '#' comments.
// Every pose is validated (finite, quaternion norm about 1, rigid). Order and duplicates are left as written.
// Throws Error whose message starts with `source` and the line at fault (see io/parsers.h).
std::vector<TimedPose> parseTrajectory(std::istream& in, const std::string& source);

}  // namespace io

}  // namespace vkmesh
