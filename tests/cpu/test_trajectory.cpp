// TUM-format trajectories (io/trajectory.h): what vkmesh writes for the poses it used, read back by vkmesh and
// by TUM's tools; the round trip, the number formats and the errors naming the file and line.
#include "io/trajectory.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace vkmesh;
using test::errorMessageOf;

namespace {

Pose poseAt(int i) {
    Pose T = Pose::Identity();
    // Rotations past 180 degrees about varied axes: the quaternion's sign (qw >= 0 is written) matters.
    T.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(0.9 * i - 2.0, Eigen::Vector3d(1, -2 + i, 3).normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(0.123456789 * i, -2.5 + 0.01 * i, 1e-4 * i);
    return T;
}

void writeFile(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

std::vector<std::string> dataLines(const fs::path& file) {
    std::istringstream in(test::readText(file));
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

}  // namespace

TEST(Trajectory, WriteThenReadRoundTrips) {
    const fs::path file = test::makeTempDir("traj") / "trajectory.txt";
    std::vector<TimedPose> poses;
    // Unix seconds with microseconds, and frame numbers.
    for (int i = 0; i < 6; ++i) poses.push_back({1305031102.175304 + 0.033 * i, poseAt(i)});
    for (int i = 0; i < 3; ++i) poses.push_back({double(1000 + i), poseAt(10 + i)});
    writeTumTrajectory(file, poses);

    const std::vector<TimedPose> back = readTumTrajectory(file);
    ASSERT_EQ(back.size(), poses.size());
    for (size_t i = 0; i < poses.size(); ++i) {
        EXPECT_NEAR(back[i].timestamp, poses[i].timestamp, 1e-6) << i;  // microseconds are what is written
        // 9 decimals: positions to 1e-9 m, the unit quaternion to 1e-9 (a rotation matrix to a few 1e-9).
        EXPECT_LT((back[i].cameraToWorld - poses[i].cameraToWorld).cwiseAbs().maxCoeff(), 1e-8)
            << i << "\n" << back[i].cameraToWorld << "\n" << poses[i].cameraToWorld;
    }
    // Written again, the file is the same to the byte: what was read is what was written.
    const fs::path again = file.parent_path() / "again.txt";
    writeTumTrajectory(again, back);
    EXPECT_EQ(test::readText(again), test::readText(file));
}

TEST(Trajectory, FileFormatIsTums) {
    const fs::path file = test::makeTempDir("traj_format") / "t.txt";
    Pose flipped = Pose::Identity();
    flipped.topLeftCorner<3, 3>() = Eigen::AngleAxisd(3.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    writeTumTrajectory(file, {{7, Pose::Identity()}, {1305031102.5, flipped}});
    const std::vector<std::string> lines = dataLines(file);
    ASSERT_EQ(lines.size(), 3u);
    EXPECT_EQ(lines[0], "# timestamp tx ty tz qx qy qz qw");
    EXPECT_EQ(lines[1], "7 0.000000000 0.000000000 0.000000000 0.000000000 0.000000000 0.000000000 1.000000000");
    // 8 fields, timestamp with 6 decimals, qw >= 0 and a unit quaternion.
    std::istringstream in(lines[2]);
    std::string t;
    double v[7];
    in >> t;
    for (double& x : v) in >> x;
    EXPECT_EQ(t, "1305031102.500000");
    EXPECT_GE(v[6], 0.0);
    EXPECT_NEAR(std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]), 1.0, 1e-8);
    EXPECT_NEAR(v[5], std::sin(1.5), 1e-9);
}

TEST(Trajectory, BadLinesAreRejectedNamingFileAndLine) {
    const fs::path dir = test::makeTempDir("traj_bad");
    const std::string good = "1.0 0 0 0 0 0 0 1\n";
    struct Case {
        std::string text, where, says;
    };
    const std::vector<Case> cases = {
        {"# header\n" + good + "2.0 0 0 0 0 0 1\n", "bad.txt:3", "got 7"},
        {good + good + "3.0 0 0 x 0 0 0 1\n", "bad.txt:3", "'x' is not a number"},
        {"\n" + good + "4.0 0 0 0 0 0 0 nan\n", "bad.txt:3", "not finite"},
        {"5.0 0 0 0 0 0 0 0\n", "bad.txt:1", "norm"},
        {good + "6.0 0 0 0 0 0 0 1 9\n", "bad.txt:2", "got 9"},
    };
    for (const Case& c : cases) {
        writeFile(dir / "bad.txt", c.text);
        const std::string msg = errorMessageOf([&] { readTumTrajectory(dir / "bad.txt"); });
        EXPECT_NE(msg.find((dir / c.where).string()), std::string::npos) << c.text << " -> " << msg;
        EXPECT_NE(msg.find(c.says), std::string::npos) << c.text << " -> " << msg;
    }
    // Comments and blank lines are skipped; an empty file is an empty trajectory.
    writeFile(dir / "ok.txt", "# a\n\n" + good + "# b\n");
    EXPECT_EQ(readTumTrajectory(dir / "ok.txt").size(), 1u);
    writeFile(dir / "empty.txt", "");
    EXPECT_TRUE(readTumTrajectory(dir / "empty.txt").empty());
    const std::string missing = errorMessageOf([&] { readTumTrajectory(dir / "missing.txt"); });
    EXPECT_NE(missing.find("missing.txt"), std::string::npos) << missing;
}

TEST(Trajectory, WritingRefusesWhatCouldNotBeReadBack) {
    const fs::path dir = test::makeTempDir("traj_refuse");
    Pose scaled = Pose::Identity();
    scaled(0, 0) = 2;
    std::string msg = errorMessageOf([&] { writeTumTrajectory(dir / "t.txt", {{0, Pose::Identity()}, {1, scaled}}); });
    EXPECT_NE(msg.find("pose 1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("orthonormal"), std::string::npos) << msg;
    EXPECT_FALSE(fs::exists(dir / "t.txt"));  // nothing half-written
    msg = errorMessageOf([&] { writeTumTrajectory(dir / "t.txt", {{std::nan(""), Pose::Identity()}}); });
    EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
    msg = errorMessageOf([&] { writeTumTrajectory(dir / "no_such_folder" / "t.txt", {}); });
    EXPECT_NE(msg.find("no_such_folder"), std::string::npos) << msg;
}
