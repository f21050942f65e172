// Fixtures the dataset tests share (test_datasets.cpp, test_dataset_errors.cpp, test_dataset_color_poseless.cpp):
// tiny TUM, ICL-NUIM, Redwood and 7-Scenes sequences written on the fly, and the checks on what Dataset reads.
#pragma once

#include "io/dataset.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace vkmesh::test::dataset_fixtures {

inline constexpr int W = 8, H = 6;

inline void writeText(const fs::path& file, const std::string& text) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
}

inline void writeDepth(const fs::path& file, const std::function<uint16_t(int, int)>& value, int w = W, int h = H) {
    fs::create_directories(file.parent_path());
    cv::Mat m(h, w, CV_16UC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) m.at<uint16_t>(y, x) = value(x, y);
    ASSERT_TRUE(cv::imwrite(file.string(), m)) << file;
}

// A raw depth ramp that differs per frame, so a test can tell frames apart.
inline uint16_t ramp(int frame, int x, int y) { return static_cast<uint16_t>(1000 + 100 * frame + 10 * x + y); }

using test::errorMessageOf;

inline bool anyContains(const std::vector<std::string>& lines, const std::string& needle) {
    return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(needle) != std::string::npos; });
}

inline std::string joinLines(const std::vector<std::string>& lines) {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
}

// The pose the TUM fixture's groundtruth holds at time t: a rotation growing with t about a fixed
// oblique axis, and a translation that also grows with t.
inline Pose tumPoseAt(double t) {
    double s = t - 100.0;
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(2.0 * s, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(s, 2 * s, 0.5);
    return T;
}

inline std::string gtLine(double t, const Pose& T) {
    Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    std::ostringstream os;
    os << std::fixed << std::setprecision(4) << t << std::setprecision(9) << " " << T(0, 3) << " " << T(1, 3) << " "
       << T(2, 3) << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
    return os.str();
}

// TUM fixture: six depth frames 4 ms after a 100 Hz groundtruth tick, except frame 3 (t = 100.30),
// whose groundtruth ticks within 30 ms were removed: it must be skipped.
struct TumFixture {
    fs::path dir;
    std::vector<double> depthTimes{100.004, 100.104, 100.204, 100.300, 100.404, 100.504};
};

inline TumFixture makeTum(const std::string& name = "rgbd_dataset_freiburg1_xyz") {
    TumFixture f;
    f.dir = test::makeTempDir("tum") / name;
    std::string depthTxt = "# depth maps\n# timestamp filename\n";
    for (size_t i = 0; i < f.depthTimes.size(); ++i) {
        std::ostringstream name;
        name << std::fixed << std::setprecision(6) << f.depthTimes[i];
        depthTxt += name.str() + " depth/" + name.str() + ".png\n";
        writeDepth(f.dir / "depth" / (name.str() + ".png"), [&](int x, int y) { return ramp(int(i), x, y); });
    }
    writeText(f.dir / "depth.txt", depthTxt);
    std::string gt = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
    for (int k = -5; k <= 60; ++k) {
        double t = 100.0 + k * 0.01;
        if (std::abs(t - 100.30) < 0.025) continue;  // the gap: nearest remaining ticks are 30 ms away
        gt += gtLine(t, tumPoseAt(t));
    }
    writeText(f.dir / "groundtruth.txt", gt);
    return f;
}

inline void expectPoseNear(const Pose& a, const Pose& b, double tol) {
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tol) << "got\n" << a << "\nexpected\n" << b;
}

// ------------------------------------------------------------------------------------------ ICL-NUIM

inline fs::path makeIcl(const std::string& name, const std::vector<int>& depthIds, const std::vector<int>& poseIds) {
    auto dir = test::makeTempDir("icl") / name;
    std::string depthTxt, gt;
    for (int i : depthIds) {
        depthTxt += std::to_string(i) + " depth/" + std::to_string(i) + ".png\n";
        writeDepth(dir / "depth" / (std::to_string(i) + ".png"), [&](int x, int y) { return ramp(i, x, y); });
    }
    for (int i : poseIds) gt += std::to_string(i) + " " + std::to_string(i) + " 0 -2.5 0 0 0 1\n";
    writeText(dir / "depth.txt", depthTxt);
    writeText(dir / "groundtruth.txt", gt);
    return dir;
}

// ------------------------------------------------------------------------------------------ Redwood

inline Pose redwoodPose(int i) {
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(0.1 * i, -0.2, 1.5);
    return T;
}

inline std::string logBlock(int id, const Pose& T) {
    std::ostringstream os;
    os << id << " " << id << " " << id + 1 << "\n" << std::setprecision(17);
    for (int r = 0; r < 4; ++r) os << T(r, 0) << " " << T(r, 1) << " " << T(r, 2) << " " << T(r, 3) << "\n";
    return os.str();
}

inline fs::path makeRedwood(const std::vector<int>& poseIds, int images = 5) {
    auto dir = test::makeTempDir("redwood") / "livingroom1";
    for (int i = 0; i < images; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        writeDepth(dir / "depth" / name, [&](int x, int y) { return ramp(i, x, y); });
    }
    std::string log;
    for (int i : poseIds) log += logBlock(i, redwoodPose(i));
    writeText(dir / "livingroom1-traj.log", log);
    return dir;
}

// ------------------------------------------------------------------------------------------ 7-Scenes

inline fs::path makeSevenScenes(fs::path dir, int frames, const std::function<std::string(int)>& poseText) {
    for (int i = 0; i < frames; ++i) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "frame-%06d", i);
        // Column x = 0 holds the "no reading" marker 65535, x = 1 holds 0, the rest i+1.5 m (mm).
        writeDepth(dir / (std::string(stem) + ".depth.png"), [&](int x, int) -> uint16_t {
            return x == 0 ? 65535 : x == 1 ? 0 : static_cast<uint16_t>(1500 + 1000 * i);
        });
        std::string pose = poseText(i);
        if (!pose.empty()) writeText(dir / (std::string(stem) + ".pose.txt"), pose);
    }
    return dir;
}

inline std::string matrixText(const Pose& T) {
    std::ostringstream os;
    os << std::setprecision(9) << std::scientific;
    for (int r = 0; r < 4; ++r) os << T(r, 0) << "\t" << T(r, 1) << "\t" << T(r, 2) << "\t" << T(r, 3) << "\t\n";
    return os.str();
}

// ------------------------------------------------------------------------------------------ real data

// The shared real sequence `name` (../shared/datasets or $VKMESH_DATASETS), or nothing where it is absent.
inline std::optional<fs::path> realDataset(const std::string& name) {
    auto root = test::sharedDatasetsDir();
    if (!root || !fs::is_directory(*root / name)) return std::nullopt;
    return *root / name;
}

}  // namespace vkmesh::test::dataset_fixtures
