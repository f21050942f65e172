// Fuzz target: the trajectory parsers. TUM groundtruth.txt / ICL-NUIM *.gt.freiburg (timestamp + quaternion
// lines), the Redwood *.log (id header + 4x4 matrix blocks) and the 7-Scenes frame-N.pose.txt (16 numbers)
// all read the same input. Every pose they return must have passed validatePose: a NaN or non-rigid pose
// that gets through is as much a bug as a crash, so the target re-checks it.
#include "fuzz_common.h"
#include "io/dataset.h"
#include "io/parsers.h"

#include <Eigen/LU>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

namespace {

void checkRigid(const vkmesh::Pose& T) {
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    if (!T.allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
        R.determinant() < 0) {
        std::fprintf(stderr, "a parser returned a pose that is not rigid\n");
        std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        std::istringstream in(text);
        for (const auto& p : vkmesh::io::parseTrajectory(in, "groundtruth.txt")) {
            checkRigid(p.cameraToWorld);
            if (!std::isfinite(p.timestamp)) std::abort();
        }
    });
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        std::istringstream in(text);
        for (const auto& p : vkmesh::io::parseRedwoodLog(in, "trajectory.log")) checkRigid(p.cameraToWorld);
    });
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        std::istringstream in(text);
        auto m = vkmesh::io::parseNumbers(in, "frame-000000.pose.txt", 16, "a 4x4 camera-to-world matrix");
        vkmesh::Pose T;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) T(r, c) = m[r * 4 + c];
        vkmesh::validatePose(T, "frame-000000.pose.txt");
        checkRigid(T);
    });
    return 0;
}
