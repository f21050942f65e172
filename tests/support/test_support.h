// Helpers shared by the tests.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <vector>

#include "core/types.h"
#include "synth/synthetic_scene.h"
#include <optional>
#include <string>

namespace vkmesh::test {

// The shared real datasets: $VKMESH_DATASETS if set, else ../shared/datasets beside the checkout.
// Returns nothing (and the caller GTEST_SKIPs with a message saying so) when the folder is absent.
std::optional<std::filesystem::path> sharedDatasetsDir();

// Non-empty (the reason) when lavapipe cannot draw vkmesh's meshes in this process: with
// LP_NATIVE_VECTOR_WIDTH below 256 (4-lane subgroups), Mesa 22.3's lavapipe writes past a heap block when
// a vertex shader reads a VK_FORMAT_R32_UINT attribute, as the mesh renderer does (Vertex::createdFrame),
// and the process aborts later, usually at exit. A Mesa bug, reproduced without vkmesh in
// docs/repro/lavapipe_width128/ (docs/PORTABILITY.md). The tests that draw GTEST_SKIP with this reason.
std::string lavapipeCannotDraw();

// A fresh empty temporary folder for one test, removed when the test program exits with every test passed (kept
// after a failure, or with VKMESH_KEEP_TEST_DIRS set, for inspection).
std::filesystem::path makeTempDir(const std::string& tag);

// Runs the vkmesh program with `args` (a shell-quoted string); returns its exit code and what it printed.
struct CliRun {
    int exitCode;
    std::string out, err;
};
CliRun runCli(const std::string& args);

// The folder `vkmesh synth <folder> <args>` writes, then `prepare` edits (if given), made once and shared by the test
// programs of one build: ctest runs each test in a program of its own, and a sequence several tests fuse took
// ~17 s to render in each. Kept in <build>/test_cache/<test program>_<name>_<key>, the key a hash of the arguments and
// of the vkmesh program's and this test program's size and time, so a rebuilt program renders it again (and the
// stale folders of `name` are removed then). Programs that ask at once may both render it: each renders into a folder of its own
// and renames it into place, the first rename wins and the others use that folder. Tests must not change it.
// A failed render is a test failure (and the folder is not shared).
std::filesystem::path sharedSynthSequence(const std::string& name, const std::string& args,
                                          const std::function<void(const std::filesystem::path&)>& prepare = {});

std::string readText(const std::filesystem::path& path);

// Writes the recordings tests/support/make_recordings.py makes of a TUM-layout `folder` (kinds as it names
// them, comma-separated) into `outDir`. Returns the reason when they cannot be made here (Debian's
// python3-rosbag, python3-zstandard, python3-lz4 or python3-pil missing: scripts/install_deps.sh installs them),
// empty on success; a failure of the script itself is a test failure.
std::string makeRecordings(const std::filesystem::path& folder, const std::filesystem::path& outDir,
                           const std::string& kinds);

// Writes `bytes` to `path` as is (binary), creating the parent folders: broken input for the
// hostile-input tests (truncated files, garbage, empty files).
void writeBytes(const std::filesystem::path& path, const std::string& bytes);

// Writes a w x h PNG of OpenCV type `cvType` (CV_16UC1 for a valid depth image; CV_8UC1, CV_16UC3, ...
// for wrong ones) with every sample `value`, creating the parent folders.
void writePng(const std::filesystem::path& path, int w, int h, int cvType, double value);

// A minimal valid TUM RGB-D sequence in a folder named "<name>" under a fresh temp dir: `frames` depth
// frames of w x h (1 m everywhere) at t = 1, 2, ..., listed in depth.txt as depth/<i>.png, and an identity
// pose translated by i along x at each t in groundtruth.txt. Tests break one of its files.
std::filesystem::path makeMinimalTum(const std::string& name, int frames = 3, int w = 8, int h = 6);

// The message of the vkmesh::Error `f` throws; records a test failure (and returns what it has) if `f`
// throws nothing or another exception.
std::string errorMessageOf(const std::function<void()>& f);

// The lines one under the other (a list of violated invariants in a failure message).
std::string joined(const std::vector<std::string>& lines);

// A camera at `eye` looking at `target`: x right, y down, z forward, world z up; a proper rotation.
Pose lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

// 48 poses orbiting `centre` at `distance`, at 6 elevations from -70 to 75 degrees, looking at the centre:
// enough views to observe a closed object's whole surface.
std::vector<Pose> orbitAround(const Eigen::Vector3d& centre, double distance);

// A torus (R 0.42 m, r 0.15 m) tilted 0.5 rad, alone in space: genus 1 for topology tests.
inline const Eigen::Vector3d kTorusCentre{-0.07, 0.11, 0.95};
synth::SyntheticScene tiltedTorus();

}  // namespace vkmesh::test
