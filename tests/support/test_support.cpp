#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <sys/wait.h>

#include <atomic>
#include <mutex>
#include <vector>
#include <fstream>
#include <sstream>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>

namespace vkmesh::test {

std::optional<std::filesystem::path> sharedDatasetsDir() {
    if (const char* env = std::getenv("VKMESH_DATASETS"); env && *env) {
        std::filesystem::path p(env);
        if (std::filesystem::is_directory(p)) return p;
        return std::nullopt;
    }
    std::filesystem::path p = std::filesystem::path(VKMESH_SOURCE_DIR) / ".." / "shared" / "datasets";
    if (std::filesystem::is_directory(p)) return std::filesystem::canonical(p);
    return std::nullopt;
}

std::string lavapipeCannotDraw() {
    const char* width = std::getenv("LP_NATIVE_VECTOR_WIDTH");
    if (!width || !*width || std::atoi(width) >= 256) return {};
    return std::string("LP_NATIVE_VECTOR_WIDTH=") + width +
           ": lavapipe (Mesa 22.3) corrupts the heap when a vertex shader reads a VK_FORMAT_R32_UINT attribute, as the "
           "mesh renderer does (tracking's model-map draw, with float and UNORM attributes only, aborts the same way); "
           "a Mesa bug, reproduced without vkmesh in docs/repro/lavapipe_width128 (docs/PORTABILITY.md)";
}

namespace {
// The folders makeTempDir made in this test program, removed when it exits with every test passed: a run of the
// suite left ~3 GB of them in the temporary folder (recorded sequences, maps, meshes), which piled up over a day's
// runs. Kept after a failure (ctest runs each test in a program of its own, so only the failed test's), or when
// VKMESH_KEEP_TEST_DIRS is set, for inspection. Destroyed before GoogleTest's UnitTest, which was made first.
struct TempDirs {
    std::mutex mutex;
    std::vector<std::filesystem::path> dirs;
    ~TempDirs() {
        if (std::getenv("VKMESH_KEEP_TEST_DIRS") || !::testing::UnitTest::GetInstance()->Passed()) return;
        for (const std::filesystem::path& dir : dirs) {
            std::error_code ignored;   // (a test that removed its folder itself)
            std::filesystem::remove_all(dir, ignored);
        }
    }
};
TempDirs& tempDirs() {
    static TempDirs dirs;
    return dirs;
}
}  // namespace

std::filesystem::path makeTempDir(const std::string& tag) {
    static std::atomic<int> counter{0};
    auto dir = std::filesystem::temp_directory_path() /
               ("vkmesh_test_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    TempDirs& made = tempDirs();
    std::lock_guard lock(made.mutex);
    made.dirs.push_back(dir);
    return dir;
}

std::string readText(const std::filesystem::path& path) {
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out) throw std::runtime_error("test support: cannot write " + path.string());
}

void writePng(const std::filesystem::path& path, int w, int h, int cvType, double value) {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    cv::Mat m(h, w, cvType, cv::Scalar::all(value));
    if (!cv::imwrite(path.string(), m)) throw std::runtime_error("test support: cannot write " + path.string());
}

std::filesystem::path makeMinimalTum(const std::string& name, int frames, int w, int h) {
    const std::filesystem::path dir = makeTempDir("hostile") / name;
    std::string depth = "# timestamp filename\n", gt = "# timestamp tx ty tz qx qy qz qw\n";
    for (int i = 0; i < frames; ++i) {
        const std::string t = std::to_string(i + 1);
        writePng(dir / "depth" / (std::to_string(i) + ".png"), w, h, CV_16UC1, 5000);
        depth += t + " depth/" + std::to_string(i) + ".png\n";
        gt += t + " " + std::to_string(i) + " 0 0 0 0 0 1\n";
    }
    writeBytes(dir / "depth.txt", depth);
    writeBytes(dir / "groundtruth.txt", gt);
    return dir;
}

std::string joined(const std::vector<std::string>& lines) {
    std::string out;
    for (const auto& l : lines) out += l + "\n";
    return out;
}

std::string errorMessageOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "threw a non-vkmesh exception: " << e.what();
        return e.what();
    }
    ADD_FAILURE() << "did not throw";
    return {};
}

std::string makeRecordings(const std::filesystem::path& folder, const std::filesystem::path& outDir,
                           const std::string& kinds) {
    const std::string python = "/usr/bin/python3";
    const std::string check = python + " -c 'import rosbag, sensor_msgs.msg, zstandard, lz4.frame, PIL, numpy' > /dev/null 2>&1";
    if (std::system(check.c_str()) != 0)
        return "the recording fixtures need python3-rosbag, python3-sensor-msgs, python3-zstandard, python3-lz4 and "
               "python3-pil (scripts/install_deps.sh installs them)";
    const std::filesystem::path log = outDir.parent_path() / (outDir.filename().string() + ".log");
    const std::string cmd = python + " " + std::string(VKMESH_SOURCE_DIR) + "/tests/support/make_recordings.py '" +
                            folder.string() + "' '" + outDir.string() + "' --kinds " + kinds + " > '" + log.string() + "' 2>&1";
    if (std::system(cmd.c_str()) != 0) ADD_FAILURE() << cmd << " failed:\n" << readText(log);
    return {};
}

CliRun runCli(const std::string& args) {
    static std::atomic<int> counter{0};
    const std::filesystem::path dir = makeTempDir("cli_run" + std::to_string(counter++));
    const std::string cmd =
        std::string(VKMESH_CLI) + " " + args + " > " + (dir / "out").string() + " 2> " + (dir / "err").string();
    const int status = std::system(cmd.c_str());
    CliRun run{WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(dir / "out"), readText(dir / "err")};
    std::filesystem::remove_all(dir);
    return run;
}

namespace {
std::string fileStamp(const std::filesystem::path& file) {
    std::error_code error;
    const auto size = std::filesystem::file_size(file, error);
    const auto time = std::filesystem::last_write_time(file, error).time_since_epoch().count();
    return std::to_string(size) + ":" + std::to_string(time);
}
}  // namespace

std::filesystem::path sharedSynthSequence(const std::string& name, const std::string& args,
                                          const std::function<void(const std::filesystem::path&)>& prepare) {
    namespace fs = std::filesystem;
    const fs::path cli = fs::absolute(VKMESH_CLI);
    const std::string stamp = args + "|" + fileStamp(cli) + "|" + fileStamp("/proc/self/exe");
    char key[17];
    std::snprintf(key, sizeof key, "%016zx", std::hash<std::string>{}(stamp));
    // Named after the test program too: two programs that chose the same name keep apart.
    const std::string prefix = fs::read_symlink("/proc/self/exe").filename().string() + "_" + name + "_";
    const fs::path cache = cli.parent_path() / "test_cache", shared = cache / (prefix + key);
    if (fs::is_directory(shared)) return shared;

    fs::create_directories(cache);
    const fs::path mine = cache / (".making_" + prefix + key + "_" + std::to_string(::getpid()));
    fs::remove_all(mine);
    fs::create_directories(mine);
    const CliRun r = runCli("synth " + mine.string() + " " + args);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    if (r.exitCode != 0) return mine;   // the failure is recorded; the folder is not shared
    if (prepare) prepare(mine);
    std::error_code error;
    fs::rename(mine, shared, error);   // fails when another program's folder is in place: use that one
    if (error) fs::remove_all(mine, error);
    // Folders of `name` that older builds of this program rendered: nothing will ask for them again.
    for (const fs::directory_entry& entry : fs::directory_iterator(cache, error)) {
        const std::string file = entry.path().filename().string();
        if (file.rfind(prefix, 0) == 0 && entry.path() != shared) fs::remove_all(entry.path(), error);
    }
    return shared;
}

Pose lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
    const Eigen::Vector3d forward = (target - eye).normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Pose pose = Pose::Identity();
    pose.topLeftCorner<3, 3>() << right, down, forward;
    pose.topRightCorner<3, 1>() = eye;
    return pose;
}

std::vector<Pose> orbitAround(const Eigen::Vector3d& centre, double distance) {
    std::vector<Pose> poses;
    const double elevations[] = {-70, -40, -10, 20, 50, 75};
    for (double elevation : elevations) {
        for (int k = 0; k < 8; ++k) {
            const double azimuth = (k + 0.5 * (elevation > 0)) * std::numbers::pi / 4;
            const double e = elevation * std::numbers::pi / 180;
            const Eigen::Vector3d eye =
                centre + distance * Eigen::Vector3d(std::cos(e) * std::cos(azimuth), std::cos(e) * std::sin(azimuth), std::sin(e));
            poses.push_back(lookAt(eye, centre));
        }
    }
    return poses;
}

synth::SyntheticScene tiltedTorus() {
    synth::Object torus;
    torus.name = "torus";
    torus.kind = synth::ObjectKind::Torus;
    torus.objectToWorld = Eigen::Isometry3d::Identity();
    torus.objectToWorld.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 0.3, 0).normalized()).toRotationMatrix();
    torus.objectToWorld.translation() = kTorusCentre;
    torus.radius = 0.42;
    torus.tubeRadius = 0.15;
    return synth::SyntheticScene({torus});
}

}  // namespace vkmesh::test
