#include "fuse_sinks.h"

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <limits>

#include "io/png.h"
#ifdef VKMESH_HAVE_VIEWER
#include "viewer/viewer_server.h"
#endif

namespace vkmesh::cli {

ProgressSink::ProgressSink(size_t datasetFrames, bool quiet) : datasetFrames_(datasetFrames), quiet_(quiet), tty_(isatty(STDERR_FILENO)) {}

void ProgressSink::warn(const std::string& warning) const {
    if (tty_ && !quiet_) std::cerr << "\n";
    std::cerr << "warning: " << warning << "\n";
}

void ProgressSink::frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume&) {
    for (const std::string& w : result.warnings) warn(w);
    if (!result.isFused()) return;
    const gpu::FrameReport& report = *result.fused;
    for (const auto& g : report.growth) {
        if (++growthLines_ < 1000 && !quiet_) {
            if (tty_) std::cerr << "\n";
            std::cerr << "note: frame " << frame.index << ": grew " << g << "\n";
        }
    }
    const size_t i = frame.index;
    if (!quiet_ && (tty_ || (i + 1) % 50 == 0 || i + 1 == datasetFrames_))
        std::fprintf(stderr, "%sframe %zu/%zu  blocks %u  %.1f ms/frame%s", tty_ ? "\r" : "", i + 1, datasetFrames_,
                     report.counters.blocksInUse, result.fuseWallMs, tty_ ? "   " : "\n");
}

PictureSink::PictureSink(const vk::Context& context, const std::string& folder, uint32_t every, const std::string& view,
                         const std::string& color, bool fusesColor, const Intrinsics& intrinsics, float maxDepth)
    : renderer_(context), folder_(folder), every_(every), view_(view), intrinsics_(intrinsics), maxDepth_(maxDepth) {
    std::filesystem::create_directories(folder_);
    options_.width = intrinsics.width;
    options_.height = intrinsics.height;
    options_.color = render::parseColorMode(color);
    if (options_.color == render::ColorMode::Auto) options_.color = fusesColor ? render::ColorMode::Rgb : render::ColorMode::Shade;
    seenMin_ = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    seenMax_ = -seenMin_;
}

void PictureSink::frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume& volume) {
    if (!result.isFused()) return;
    ++fused_;
    const Pose& pose = result.cameraToWorld;
    const Eigen::Vector3f eye = pose.block<3, 1>(0, 3).cast<float>();
    seenMin_ = seenMin_.cwiseMin(eye - Eigen::Vector3f::Constant(maxDepth_));
    seenMax_ = seenMax_.cwiseMax(eye + Eigen::Vector3f::Constant(maxDepth_));
    if (fused_ % every_ != 0 || volume.meshBuffers().triangleCount == 0) return;
    Eigen::Vector3f lo = seenMin_, hi = seenMax_;
    if (view_ == "sensor") {
        options_.camera = render::sensorCamera(pose, intrinsics_);
    } else {
        // The overview frames the mesh built so far, so its bounds are read (one small download).
        gpu::ExportedMesh sofar = volume.exportMesh();
        lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
        for (const auto& v : sofar.vertices) lo = lo.cwiseMin(Eigen::Vector3f(v.px, v.py, v.pz)), hi = hi.cwiseMax(Eigen::Vector3f(v.px, v.py, v.pz));
        options_.camera = render::defaultCamera(lo, hi, options_.width, options_.height);
    }
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%06u.png", frame.index);
    io::writePng(folder_ / name, renderer_.render(volume.meshBuffers(), lo, hi, options_));
    ++written_;
}

#ifdef VKMESH_HAVE_VIEWER
void ViewerSink::frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume&) {
    if (!result.isFused()) return;
    server_.publish(result.fused->delta, viewer::fusedFrameInfo(frame.index + 1 - firstFrame_, frames_ - firstFrame_, result.fuseWallMs,
                                                                result.fused->counters.blocksInUse, result.cameraToWorld, frame.intrinsics));
}
#endif

}  // namespace vkmesh::cli
