// PyReconstructor (py_reconstructor.cpp): what vkmesh.Reconstructor wraps, a vkmesh::Reconstructor used by one thread
// at a time with the GIL released, its arguments checked and converted, its results as numpy arrays and dicts.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "api/reconstructor.h"
#include "arrays.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "vk/context.h"
#ifdef VKMESH_HAVE_VIEWER
#include "viewer/viewer_server.h"
#endif

namespace vkmesh::python {

class PyReconstructor {
public:
    PyReconstructor(const ReconstructorOptions& options, std::unique_ptr<Reconstructor> rec)
        : options_(options), rec_(std::move(rec)) {}

    // Runs f on the Reconstructor with the GIL released and the object's mutex held; then publishes the
    // validation messages the call produced. f must not touch Python objects.
    template <class F>
    auto locked(F&& f) {
        std::vector<std::string> messages;
        auto takeMessages = [&] {
            if (rec_) messages = rec_->context().takeValidationMessages();
        };
        struct Publish {   // also when f throws
            std::vector<std::string>& messages;
            ~Publish() { publishMessages(std::move(messages)); }
        } publish{messages};
        py::gil_scoped_release release;
        std::lock_guard<std::mutex> lock(mutex_);
        if (!rec_) throw Error("this Reconstructor is closed");
        try {
            if constexpr (std::is_void_v<decltype(f(*rec_))>) {
                f(*rec_);
                takeMessages();
            } else {
                auto result = f(*rec_);
                takeMessages();
                return result;
            }
        } catch (...) {
            takeMessages();
            throw;
        }
    }

    // py::object rather than py::array: any array-like is accepted, and a wrong one is a ValueError naming it.
    // pose None: the camera is tracked (Reconstructor::integrate without a pose); returns what tracking did.
    py::object integrate(const py::object& depthObject, const py::object& intrinsicsObject, const py::object& poseObject,
                         double depthScale, const py::object& colorObject);

    // New poses for fused frames (Reconstructor::correct): indices (N,) and poses (N, 4, 4), all checked first.
    void correct(const py::object& framesObject, const py::object& posesObject);

    size_t pendingCorrections();

    py::dict finishCorrections();

    py::dict lastCorrections();

    static py::dict correctionDict(const gpu::CorrectionReport& r);

    // Every frame's camera-to-world pose so far (given, tracked, or predicted for a lost frame): N x 4 x 4.
    py::array trajectory();

    py::object mesh();

    py::object deltas();

    // The library's run statistics (api/run_stats_json.h: the keys of `vkmesh fuse --stats`), with this module's own
    // keys as they have always been (the settings as Python shows floats, the last frame); where both have a key,
    // this module's value stays, so that no key a script reads changes.
    py::dict stats();

    // `own` with every key of the run statistics it lacks, at any depth (json.loads of `runJson`).
    static py::dict withRunStats(py::dict own, const std::string& runJson);
    static void addMissing(py::dict& into, const py::dict& from);

    void save(const fs::path& path);

    void close();

    // The live browser viewer (docs/VIEWER.md) on a server thread of its own, fed each frame's delta by integrate().
    std::string serve(int port, const std::string& host);

    py::dict stopServing();
    bool closed();
    uint32_t framesIntegrated();
    std::string repr();

    // For the overhead benchmark (bench/python_overhead.py): how long the last integrate() spent in the C++ API's
    // Reconstructor::integrate; the rest of its wall time is the module's.
    double lastCppSeconds();

    // For the overhead benchmark: the C++ API's integrate on a frame converted beforehand, timed in C++.
    double timedCppIntegrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& pose);

private:
    // Depth beyond this is no measurement (the volume's max depth: the constructor's, or a loaded map's).
    float maxDepth(Reconstructor& rec) const;

    ReconstructorOptions options_;
#ifdef VKMESH_HAVE_VIEWER
    std::optional<viewer::Server> server_;   // holds copies of the deltas only: independent of rec_'s lifetime
#endif
    std::unique_ptr<Reconstructor> rec_;
    std::mutex mutex_;
    // Reused from frame to frame (guarded by mutex_): no allocation per call once the first frame has run.
    DepthImage depth_;
    ColorImage color_;
    gpu::FrameReport lastReport_;
    double lastCppSeconds_ = 0;
};

}  // namespace vkmesh::python
