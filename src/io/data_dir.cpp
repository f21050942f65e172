#include "io/data_dir.h"

#include <cstdlib>
#include <system_error>

#include "core/types.h"

namespace vkmesh::io {

namespace fs = std::filesystem;

namespace {

// The running program's path (Linux: /proc/self/exe); empty where the platform does not say.
fs::path executablePath() {
    std::error_code ec;
    fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : exe;
}

}  // namespace

std::vector<fs::path> dataDirCandidates() {
    const char* env = std::getenv("VKMESH_DATA_DIR");
    if (env && *env) return {fs::path(env)};
    std::vector<fs::path> dirs;
    if (fs::path exe = executablePath(); !exe.empty()) {
        // <prefix>/<bindir>/vkmesh -> <prefix>: one step up per component of the install's bin directory.
        fs::path prefix = exe.parent_path();
        for (const auto& component : fs::path(VKMESH_INSTALL_BIN_DIR))
            if (!component.empty()) prefix = prefix.parent_path();
        dirs.push_back(prefix / VKMESH_INSTALL_DATA_DIR);
    }
    dirs.push_back(fs::path(VKMESH_SOURCE_DATA_DIR));
    dirs.push_back(fs::path(VKMESH_INSTALL_FULL_DATA_DIR));
    return dirs;
}

fs::path findDataFile(const std::string& relative) {
    const std::vector<fs::path> dirs = dataDirCandidates();
    std::string searched;
    for (const fs::path& dir : dirs) {
        std::error_code ec;
        if (fs::is_regular_file(dir / relative, ec)) return dir / relative;
        searched += (searched.empty() ? "" : ", ") + (dir / relative).string();
    }
    const char* env = std::getenv("VKMESH_DATA_DIR");
    throw Error("vkmesh data file " + relative + " not found (looked for " + searched + ")" +
                (env && *env ? std::string("; VKMESH_DATA_DIR names a folder without it")
                             : std::string("; set VKMESH_DATA_DIR to the folder holding vkmesh's data/ files "
                                           "(installed: <prefix>/share/vkmesh)")));
}

}  // namespace vkmesh::io
