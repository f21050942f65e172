// Helpers shared by the tests.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <vector>

#include "core/types.h"
#include "synth/synthetic_scene.h"
#include <optional>
#include <string>

namespace vkmesh::test {

// The shared real datasets: $VKMESH_DATASETS if set, else ../shared/datasets beside the checkout.
// Returns nothing (and the caller GTEST_SKIPs with a message saying so) when the folder is absent.
std::optional<std::filesystem::path> sharedDatasetsDir();

// A fresh empty temporary folder for one test, removed by the caller or left for inspection.
std::filesystem::path makeTempDir(const std::string& tag);

// Runs the vkmesh program with `args` (a shell-quoted string); returns its exit code and what it printed.
struct CliRun {
    int exitCode;
    std::string out, err;
};
CliRun runCli(const std::string& args);

std::string readText(const std::filesystem::path& path);

// A camera at `eye` looking at `target`: x right, y down, z forward, world z up; a proper rotation.
Pose lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

// 48 poses orbiting `centre` at `distance`, at 6 elevations from -70 to 75 degrees, looking at the centre:
// enough views to observe a closed object's whole surface.
std::vector<Pose> orbitAround(const Eigen::Vector3d& centre, double distance);

// A torus (R 0.42 m, r 0.15 m) tilted 0.5 rad, alone in space: genus 1 for topology tests.
inline const Eigen::Vector3d kTorusCentre{-0.07, 0.11, 0.95};
synth::SyntheticScene tiltedTorus();

}  // namespace vkmesh::test
