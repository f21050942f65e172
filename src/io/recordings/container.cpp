// Container::describe, detectContainer and openContainer: the dispatch to the per-format readers
// (ros1_bag.cpp, mcap.cpp, rosbag2_sqlite.cpp).
#include "io/recordings/container.h"

#include "io/recordings/openers.h"

#include <fstream>

namespace vkmesh::io::recording {

namespace fs = std::filesystem;

std::string detail::normaliseRosType(std::string name) {
    size_t p = name.find("/msg/");
    if (p != std::string::npos) name.erase(p, 4);
    return name;
}

std::string Container::describe(const MessageRef& message) const {
    std::string s = path_.filename().string();
    // Its index when `message` is one of messages() (not a copy): the number a user sees in listings.
    if (!messages_.empty() && &message >= messages_.data() && &message < messages_.data() + messages_.size())
        s += ", message " + std::to_string(&message - messages_.data());
    else
        s += ", message";
    if (message.connection < connections_.size())
        s += " on " + connections_[message.connection].topic;
    else
        s += " on connection " + std::to_string(message.connection) + " (not in this recording)";
    return s + " (" + describeLocation(message) + ")";
}

namespace {

std::string firstBytes(const fs::path& path, size_t n) {
    std::ifstream in(path, std::ios::binary);
    std::string s(n, '\0');
    in.read(s.data(), static_cast<std::streamsize>(n));
    s.resize(static_cast<size_t>(std::max<std::streamsize>(in.gcount(), 0)));
    return s;
}

const std::string kRos1Magic = "#ROSBAG V2.0\n";
const std::string kMcapMagic = std::string("\x89MCAP0\r\n", 8);
const std::string kSqliteMagic = std::string("SQLite format 3\0", 16);

}  // namespace

ContainerKind detectContainer(const fs::path& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        if (!fs::is_regular_file(path / "metadata.yaml", ec)) return ContainerKind::None;
        try {
            return detail::readRosbag2Folder(path).storage == "mcap" ? ContainerKind::Mcap
                                                                     : ContainerKind::Rosbag2Sqlite;
        } catch (const Error&) {
            return ContainerKind::None;
        }
    }
    if (!fs::is_regular_file(path, ec)) return ContainerKind::None;
    std::string head = firstBytes(path, 16);
    if (head.starts_with(kRos1Magic)) return ContainerKind::Ros1Bag;
    if (head.starts_with(kMcapMagic)) return ContainerKind::Mcap;
    if (head == kSqliteMagic) return ContainerKind::Rosbag2Sqlite;
    return ContainerKind::None;
}

std::unique_ptr<Container> openContainer(const fs::path& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        if (!fs::is_regular_file(path / "metadata.yaml", ec))
            throw Error(path.string() + ": a folder without metadata.yaml is not a rosbag2 recording");
        detail::Rosbag2Folder folder = detail::readRosbag2Folder(path);
        if (folder.storage == "mcap") {
            // Split MCAP rosbag2 recordings would need the messages of several files merged: not done yet.
            if (folder.files.size() != 1)
                throw Error(path.string() + ": a rosbag2 recording split over " + std::to_string(folder.files.size()) +
                            " MCAP files (vkmesh reads a single one)");
            return detail::openMcapFile(folder.files.front());
        }
        return detail::openRosbag2Sqlite(path, folder.files);
    }
    if (!fs::exists(path, ec)) throw Error(path.string() + ": no such file or folder");
    switch (detectContainer(path)) {
    case ContainerKind::Ros1Bag: return detail::openRos1BagFile(path);
    case ContainerKind::Mcap: return detail::openMcapFile(path);
    case ContainerKind::Rosbag2Sqlite: return detail::openRosbag2Sqlite(path, {path});
    case ContainerKind::None: break;
    }
    std::string head = firstBytes(path, 16);
    if (head.starts_with("#ROSBAG V"))
        throw Error(path.string() + ": a ROS bag of version " + head.substr(9, head.find('\n') - 9) +
                    " (vkmesh reads version 2.0, written since ROS C Turtle)");
    throw Error(path.string() + ": not a recording vkmesh reads (neither a ROS 1 bag 2.0, an MCAP file, a rosbag2 " +
                "SQLite .db3 nor a rosbag2 folder)");
}

}  // namespace vkmesh::io::recording
