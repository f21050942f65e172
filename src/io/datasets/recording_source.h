// Internal to Dataset (src/io/dataset.cpp): a recording (ROS 1 bag, librealsense's bag, MCAP, rosbag2) read as a
// depth sequence. readRecording chooses the depth, colour and camera-info topics (by message type, or as the
// options name them), pairs colour with depth by time, reads the intrinsics, the depth unit, the extrinsics
// between the depth and colour cameras and the camera poses in /tf; RecordingSource then decodes frames on
// demand, from any thread.
#pragma once

#include "io/color_registration.h"
#include "io/datasets/layout_reader.h"
#include "io/recordings/container.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vkmesh::datasets {

namespace recording = io::recording;

class RecordingSource {
public:
    struct Frame {
        recording::MessageRef depth;
        std::optional<recording::MessageRef> color;
    };

    // Frame i's depth in metres (16-bit samples divided by depthScale; 32-bit floats as they are; NaN, inf,
    // 0 and negative values mean no measurement; samples beyond maxDepth > 0 become 0). Throws Error naming the
    // recording, the message and what is wrong with it.
    DepthImage loadDepth(size_t i, double depthScale, float maxDepth) const;
    // Frame i's colour image as recorded (RGB8), its own size. Throws Error like loadDepth.
    ColorImage loadColor(size_t i) const;
    // "message 12 on /camera/depth/image" for FrameInfo and messages.
    std::string describe(const recording::MessageRef& message) const { return container->describe(message); }

    std::unique_ptr<recording::Container> container;
    std::vector<Frame> frames;  // Dataset's frames, in the same order
};

// Opens `path` (a recording file, or a rosbag2 folder) as a Layout with Layout::recording set. Throws Error
// naming the recording and the topic, message or value at fault.
Layout readRecording(const fs::path& path, const DatasetOptions& options);

}  // namespace vkmesh::datasets
