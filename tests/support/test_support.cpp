#include "test_support.h"

#include <atomic>
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

std::filesystem::path makeTempDir(const std::string& tag) {
    static std::atomic<int> counter{0};
    auto dir = std::filesystem::temp_directory_path() /
               ("vkmesh_test_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

}  // namespace vkmesh::test
