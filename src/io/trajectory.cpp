#include "io/trajectory.h"

#include "io/text_lines.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>

namespace vkmesh {

namespace fs = std::filesystem;
using namespace io::text;

namespace {

Pose poseFromQuaternion(double tx, double ty, double tz, double qx, double qy, double qz, double qw,
                        const std::string& where) {
    Eigen::Quaterniond q(qw, qx, qy, qz);
    double n = q.norm();
    // Files round the quaternion to 4-6 digits, so it is only approximately unit; a norm far from 1 means
    // the line is corrupt (swapped columns, a zeroed field), not a rounding issue.
    if (!std::isfinite(n) || n < 0.5 || n > 2.0)
        throw Error(where + ": quaternion (" + fmt(qx) + " " + fmt(qy) + " " + fmt(qz) + " " + fmt(qw) +
                    ") has norm " + fmt(n) + "; expected about 1");
    q.normalize();
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = q.toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(tx, ty, tz);
    return T;
}

// Frame numbers stay integers so that a trajectory of frame-numbered poses (7-Scenes, Redwood, a folder of
// images) reads back with the same numbers; anything else is Unix time in seconds, to the microsecond.
std::string formatTimestamp(double t) {
    if (t == std::floor(t) && std::abs(t) < 1e15) return std::to_string(static_cast<long long>(t));
    return fmtFixed(t, 6);
}

}  // namespace

namespace io {

std::vector<TimedPose> parseTrajectory(std::istream& in, const std::string& source) {
    std::vector<TimedPose> out;
    for (const auto& l : readDataLines(in, source)) {
        if (l.tokens.size() != 8)
            throw Error(at(source, l.number) + ": expected 8 values 'timestamp tx ty tz qx qy qz qw', got " +
                        std::to_string(l.tokens.size()));
        double v[8];
        for (int k = 0; k < 8; ++k) {
            if (!parseNumber(l.tokens[k], v[k]))
                throw Error(at(source, l.number) + ": '" + l.tokens[k] + "' is not a number");
            if (!std::isfinite(v[k]))
                throw Error(at(source, l.number) + ": value '" + l.tokens[k] + "' is not finite");
        }
        std::string where = at(source, l.number);
        Pose T = poseFromQuaternion(v[1], v[2], v[3], v[4], v[5], v[6], v[7], where);
        validatePose(T, where);
        out.push_back({{v[0], T}, l.number});
    }
    return out;
}

}  // namespace io

void writeTumTrajectory(const fs::path& file, const std::vector<TimedPose>& poses) {
    // Everything is checked before the file is touched: a half-written trajectory is worse than none.
    for (size_t i = 0; i < poses.size(); ++i) {
        const std::string where = file.string() + ": pose " + std::to_string(i);
        if (!std::isfinite(poses[i].timestamp))
            throw Error(where + " has timestamp " + fmt(poses[i].timestamp) + ", which is not finite");
        validatePose(poses[i].cameraToWorld, where + " (timestamp " + fmtTime(poses[i].timestamp) + ")");
    }
    std::ofstream out(file);
    if (!out) throw Error("cannot write trajectory " + file.string());
    out << "# timestamp tx ty tz qx qy qz qw\n";
    for (const TimedPose& p : poses) {
        const Pose& T = p.cameraToWorld;
        Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
        q.normalize();
        if (q.w() < 0) q.coeffs() = -q.coeffs();  // q and -q are the same rotation; one sign for tidy files
        char line[256];
        std::snprintf(line, sizeof line, "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", formatTimestamp(p.timestamp).c_str(),
                      T(0, 3), T(1, 3), T(2, 3), q.x(), q.y(), q.z(), q.w());
        out << line;
    }
    out.flush();
    if (!out) throw Error("error while writing trajectory " + file.string() + " (disk full?)");
}

std::vector<TimedPose> readTumTrajectory(const fs::path& file) {
    std::ifstream in = openText(file);
    std::vector<TimedPose> out;
    for (io::TimedPose& p : io::parseTrajectory(in, file.string())) out.push_back(p);
    return out;
}

void validatePose(const Pose& pose, const std::string& where) {
    if (!pose.allFinite()) throw Error(where + ": pose has non-finite entries");
    Eigen::RowVector4d bottom = pose.row(3);
    // Files write the last row as literal 0 0 0 1; allow only print rounding.
    if ((bottom - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
        throw Error(where + ": pose bottom row is " + fmt(bottom[0]) + " " + fmt(bottom[1]) + " " + fmt(bottom[2]) +
                    " " + fmt(bottom[3]) + "; expected 0 0 0 1");
    Eigen::Matrix3d R = pose.topLeftCorner<3, 3>();
    double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (err > 1e-3)
        throw Error(where + ": pose rotation is not orthonormal (max |R^T R - I| = " + fmt(err) + ")");
    // Orthonormal leaves det = +1 (rotation) or -1 (a mirror, e.g. a flipped axis convention).
    if (R.determinant() < 0) throw Error(where + ": pose rotation has determinant -1 (a reflection, not a rotation)");
}

}  // namespace vkmesh
