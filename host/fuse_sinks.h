// What `vkmesh fuse` does with each frame the Mapper (api/mapper.h) finished: a progress line and the warnings on
// stderr, the poses as fused (--trajectory-online), the mesh-delta stream (--deltas), pictures drawn from the GPU
// mesh buffers (--render-every) and the live viewer (--serve). Each is a FrameSink; runFuse attaches the ones asked for.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/mapper.h"
#include "io/delta_stream.h"
#include "io/trajectory.h"
#include "render/mesh_renderer.h"

namespace vkmesh::viewer {
class Server;
}

namespace vkmesh::cli {

// "frame i/n  blocks b  x ms/frame" (on a terminal every frame, else every 50th), the frames' warnings and what grew.
class ProgressSink final : public FrameSink {
public:
    ProgressSink(size_t datasetFrames, bool quiet);
    void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume& volume) override;
    // A warning of the command's own (a frame it could not read), printed the same way.
    void warn(const std::string& warning) const;
    bool tty() const { return tty_; }

private:
    size_t datasetFrames_;
    bool quiet_, tty_;
    size_t growthLines_ = 0;
};

// The pose of every frame as it was when the frame was fused (or lost), before any loop's correction.
class OnlineTrajectorySink final : public FrameSink {
public:
    void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume&) override {
        if (result.posed) poses_.push_back({frame.timestamp, result.cameraToWorld});
    }
    const std::vector<TimedPose>& poses() const { return poses_; }

private:
    std::vector<TimedPose> poses_;
};

// Every fused frame's mesh changes, appended to a stream file (docs/DELTAS.md).
class DeltaStreamSink final : public FrameSink {
public:
    explicit DeltaStreamSink(const std::string& path) : writer_(path) {}
    void frameDone(const MapperResult& result, const MapperFrame&, gpu::GpuVolume&) override {
        if (result.isFused()) writer_.write(result.fused->delta);
    }
    uint64_t bytesWritten() const { return writer_.bytesWritten(); }

private:
    DeltaStreamWriter writer_;
};

// A picture of the mesh every `every` fused frames, drawn from the volume's GPU mesh buffers: from the frame's
// camera ("sensor") or framing the mesh so far ("overview").
class PictureSink final : public FrameSink {
public:
    PictureSink(const vk::Context& context, const std::string& folder, uint32_t every, const std::string& view, const std::string& color,
                bool fusesColor, const Intrinsics& intrinsics, float maxDepth);
    void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume& volume) override;
    size_t written() const { return written_; }

private:
    render::MeshRenderer renderer_;
    render::RenderOptions options_;
    std::filesystem::path folder_;
    uint32_t every_;
    std::string view_;
    Intrinsics intrinsics_;
    float maxDepth_;
    size_t fused_ = 0, written_ = 0;
    // Near/far planes of the sensor view: everything the sensor can see lies within maxDepth of a camera.
    Eigen::Vector3f seenMin_, seenMax_;
};

#ifdef VKMESH_HAVE_VIEWER
// Posts every fused frame's delta to the live viewer's server thread (a copy: a slow page never holds fusion up).
class ViewerSink final : public FrameSink {
public:
    ViewerSink(viewer::Server& server, uint32_t firstFrame, uint32_t datasetFrames) : server_(server), firstFrame_(firstFrame), frames_(datasetFrames) {}
    void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume&) override;

private:
    viewer::Server& server_;
    uint32_t firstFrame_, frames_;
};
#endif

}  // namespace vkmesh::cli
