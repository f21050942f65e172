// Recording containers: ROS 1 bag 2.0, MCAP and rosbag2 SQLite (.db3). A container is opened once, which
// indexes every message (topic, time, where its bytes are) without decoding any; a message's serialised bytes
// are then read on demand (Container::read), from any thread. The message bytes are decoded by
// io/recordings/messages.h. The containers' compression and storage use Debian's libraries (bz2, lz4, zstd,
// SQLite); the container formats are open specifications, read here (docs/RECORDINGS.md).
//
// Every function throws vkmesh::Error naming the file and the record at fault (byte offset, chunk, row) for
// a truncated, corrupt or hostile file: nothing else escapes, on any input (fuzz/fuzz_ros1_bag.cpp, fuzz/fuzz_mcap.cpp).
#pragma once

#include "core/types.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace vkmesh::io::recording {

// How a topic's messages are serialised.
enum class Serialization { Ros1, Cdr };

// A topic as the container declares it: a ROS 1 connection, an MCAP channel with its schema, a rosbag2 topic.
// Several ROS 1 connections on the same topic (several publishers) are merged into one Connection, as are
// MCAP channels and rosbag2 split files' topics: one Connection per topic, type and encoding.
struct Connection {
    uint32_t id = 0;      // its index in Container::connections()
    std::string topic;    // "/camera/depth/image"
    // The message type, normalised to ROS 1 spelling: "sensor_msgs/Image" (ROS 2's "sensor_msgs/msg/Image" too).
    std::string type;
    Serialization serialization = Serialization::Ros1;
    uint64_t messageCount = 0;
    // The serialisation as the container names it: "ros1" (every ROS 1 bag), "cdr", or another (an MCAP
    // channel's message_encoding "protobuf", "json", ...; a rosbag2 topic's serialization_format). Only "ros1"
    // and "cdr" can be decoded (messages.h); `serialization` is meaningful only for those two.
    std::string encoding;
};

// One message, located but not read.
struct MessageRef {
    uint32_t connection = 0;  // index into Container::connections()
    uint64_t logTimeNs = 0;   // when it was recorded (ROS 1 record time, MCAP log_time, rosbag2 timestamp)
    // Where the container finds its bytes: ROS 1 and MCAP: the chunk's (or, unchunked, the record's) byte
    // offset in the file and the message's offset inside the decompressed chunk (0 unchunked); rosbag2: the
    // .db3 file's index among the recording's files (split recordings) and the message's row id.
    uint64_t location[2] = {0, 0};
    // The message's first bytes where indexing had them in hand (ROS 1 and MCAP chunks: the scan decompresses
    // each chunk once), headSize of them (0: none): enough for a sensor_msgs message's header (stamp and frame id),
    // so that a dataset pairs and poses its images without reading each one a second time (decodeLeadingHeader).
    static constexpr size_t kHeadBytes = 64;
    std::array<uint8_t, kHeadBytes> head{};
    uint8_t headSize = 0;
    void keepHead(std::string_view data) {
        headSize = uint8_t(std::min(data.size(), kHeadBytes));
        std::copy_n(data.begin(), headSize, head.begin());
    }
};

class Container {
public:
    virtual ~Container() = default;

    // "ROS 1 bag", "MCAP", "rosbag2 SQLite"
    virtual std::string formatName() const = 0;
    const std::filesystem::path& path() const { return path_; }
    const std::vector<Connection>& connections() const { return connections_; }
    // Every message, sorted by logTimeNs (ties keep the file's order).
    const std::vector<MessageRef>& messages() const { return messages_; }

    // The message's serialised bytes (for CDR, with its 4-byte encapsulation header). Thread-safe: each call
    // reads the file on its own (or through a lock). Throws Error naming the file and the record.
    virtual std::vector<uint8_t> read(const MessageRef& message) const = 0;

    // "recording.bag, message 12 on /camera/depth/image (chunk at byte 4096)": for error messages.
    std::string describe(const MessageRef& message) const;

    // What indexing found wrong but could read past: a recording cut off inside its last chunk (its complete
    // chunks are indexed, the rest is lost), an MCAP without its footer. Empty for a sound file.
    const std::vector<std::string>& warnings() const { return warnings_; }

protected:
    // "chunk at byte 4096, message at 1200 inside it", "row 17 of b_1.db3": the part of describe() after the topic.
    virtual std::string describeLocation(const MessageRef& message) const = 0;

    std::vector<std::string> warnings_;
    std::filesystem::path path_;
    std::vector<Connection> connections_;
    std::vector<MessageRef> messages_;
};

// Which container `path` is, by its first bytes ("#ROSBAG V2.0\n", MCAP's magic, "SQLite format 3\0"), or a
// rosbag2 folder (metadata.yaml beside its .db3 or .mcap file: Rosbag2Sqlite or Mcap by the files it holds,
// as that is the format openContainer reads). None when it is not a recording.
enum class ContainerKind { None, Ros1Bag, Mcap, Rosbag2Sqlite };
ContainerKind detectContainer(const std::filesystem::path& path);

// Opens and indexes a recording of any kind above. Throws Error naming the file when it is none of them, or
// when it is truncated or corrupt, or uses a compression vkmesh cannot read (naming it and the record).
std::unique_ptr<Container> openContainer(const std::filesystem::path& path);

// The same on bytes in memory (fuzz targets, tests); `name` only names the source in messages. The container
// keeps its own copy. (rosbag2 SQLite: written to a temporary file, as SQLite reads files.)
std::unique_ptr<Container> openRos1Bag(std::string_view bytes, const std::string& name);
std::unique_ptr<Container> openMcap(std::string_view bytes, const std::string& name);

}  // namespace vkmesh::io::recording
