// Helpers shared by the tests.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace vkmesh::test {

// The shared real datasets: $VKMESH_DATASETS if set, else ../shared/datasets beside the checkout.
// Returns nothing (and the caller GTEST_SKIPs with a message saying so) when the folder is absent.
std::optional<std::filesystem::path> sharedDatasetsDir();

// A fresh empty temporary folder for one test, removed by the caller or left for inspection.
std::filesystem::path makeTempDir(const std::string& tag);

}  // namespace vkmesh::test
