// Where vkmesh's data files are (the top-level data/ folder of the source tree, installed as
// <prefix>/share/vkmesh): camera presets (cameras/<name>/camera.json) and whatever else data/ holds.
//
// Looked up in this order, the first folder that holds the requested file wins:
//   1. $VKMESH_DATA_DIR, when set (and then only there: a user who names a folder means that folder);
//   2. <executable>/../share/vkmesh: the installed layout (bin/vkmesh next to share/vkmesh);
//   3. the source tree's data/ that this library was built from (programs run from the build tree);
//   4. the configured install prefix's share/vkmesh (an application linking the installed library).
// Part of the vkmesh_io library.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace vkmesh::io {

// The folders searched, in order (see above); an unset or empty VKMESH_DATA_DIR is skipped.
std::vector<std::filesystem::path> dataDirCandidates();

// The path of data file `relative` (e.g. "cameras/tum_fr1/camera.json"). Throws Error naming the file and
// every folder searched when none holds it.
std::filesystem::path findDataFile(const std::string& relative);

}  // namespace vkmesh::io
