// Internal to src/io/recordings: the per-format openers that openContainer (container.cpp) dispatches to.
#pragma once

#include "io/recordings/container.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace vkmesh::io::recording::detail {

std::unique_ptr<Container> openRos1BagFile(const std::filesystem::path& path);
std::unique_ptr<Container> openMcapFile(const std::filesystem::path& path);
// One .db3 file, or the .db3 files of a rosbag2 folder in order (split bags); `path` names the recording.
std::unique_ptr<Container> openRosbag2Sqlite(const std::filesystem::path& path,
                                             const std::vector<std::filesystem::path>& files);

// A ROS 2 type name in ROS 1 spelling: "sensor_msgs/msg/Image" -> "sensor_msgs/Image" (Connection::type).
std::string normaliseRosType(std::string name);

// A rosbag2 folder's storage files, in the order metadata.yaml lists them (relative_file_paths), or by name
// when it lists none; `storage` is "sqlite3" or "mcap" (metadata.yaml's storage_identifier, or by the files'
// extension). Throws Error naming the folder when it holds no storage file.
struct Rosbag2Folder {
    std::string storage;
    std::vector<std::filesystem::path> files;
};
Rosbag2Folder readRosbag2Folder(const std::filesystem::path& dir);

}  // namespace vkmesh::io::recording::detail
