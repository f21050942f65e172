// Decoders for the messages vkmesh reads from recordings, in both serialisations: ROS 1 (little-endian,
// uint32 length-prefixed strings and arrays, no padding) and CDR (ROS 2: a 4-byte encapsulation header,
// little- or big-endian by that header, fields aligned to their size relative to the end of the header,
// strings with a terminating NUL counted in their length).
//
// Every decoder throws vkmesh::Error starting with `where` (the file and record, from Container::describe)
// for a message that is truncated, has trailing garbage where the layout allows none, or holds impossible
// values (a string longer than the message, an image whose step * height exceeds its data); never anything
// else (fuzz/fuzz_ros_messages.cpp).
#pragma once

#include "io/recordings/container.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vkmesh::io::recording {

struct MessageHeader {
    uint64_t stampNs = 0;  // header.stamp (ROS 1 time: uint32 sec, nsec; ROS 2: int32 sec, uint32 nanosec)
    std::string frameId;
};

// sensor_msgs/Image
struct ImageMessage {
    MessageHeader header;
    uint32_t height = 0, width = 0;
    std::string encoding;  // "16UC1", "mono16", "32FC1", "rgb8", ...
    bool bigEndian = false;
    uint32_t step = 0;     // bytes per row; checked: step >= width * bytes per pixel of a known encoding is
                           // the reader's job, step * height <= data.size() is checked here
    std::vector<uint8_t> data;
};

// sensor_msgs/CameraInfo (ROS 1 capitals D K R P and ROS 2 d k r p are the same fields)
struct CameraInfoMessage {
    MessageHeader header;
    uint32_t height = 0, width = 0;
    std::string distortionModel;
    std::vector<double> d;
    std::array<double, 9> k{};   // row-major 3x3: fx 0 cx / 0 fy cy / 0 0 1
    std::array<double, 9> r{};
    std::array<double, 12> p{};
};

// geometry_msgs/Transform (translation x y z, rotation quaternion x y z w)
struct TransformMessage {
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

// geometry_msgs/TransformStamped: the transform that takes points in childFrameId to header.frameId.
struct TransformStampedMessage {
    MessageHeader header;
    std::string childFrameId;
    TransformMessage transform;
};

// diagnostic_msgs/KeyValue (librealsense's device and stream information)
struct KeyValueMessage {
    std::string key, value;
};

ImageMessage decodeImage(std::span<const uint8_t> bytes, Serialization s, const std::string& where);
// The std_msgs/Header a message starts with (Image, CameraInfo, ...), from its first bytes (MessageRef::head);
// nothing when those bytes do not hold all of it. Never throws.
std::optional<MessageHeader> decodeLeadingHeader(std::span<const uint8_t> head, Serialization s);
CameraInfoMessage decodeCameraInfo(std::span<const uint8_t> bytes, Serialization s, const std::string& where);
// tf2_msgs/TFMessage (and ROS 1's tf/tfMessage, the same layout): its transforms.
std::vector<TransformStampedMessage> decodeTfMessage(std::span<const uint8_t> bytes, Serialization s,
                                                     const std::string& where);
TransformMessage decodeTransform(std::span<const uint8_t> bytes, Serialization s, const std::string& where);
float decodeFloat32(std::span<const uint8_t> bytes, Serialization s, const std::string& where);     // std_msgs/Float32
uint32_t decodeUInt32(std::span<const uint8_t> bytes, Serialization s, const std::string& where);   // std_msgs/UInt32
std::string decodeString(std::span<const uint8_t> bytes, Serialization s, const std::string& where);  // std_msgs/String
KeyValueMessage decodeKeyValue(std::span<const uint8_t> bytes, Serialization s, const std::string& where);

}  // namespace vkmesh::io::recording
