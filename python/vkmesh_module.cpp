// vkmesh._vkmesh: the compiled half of the Python package `vkmesh` (docs/PYTHON.md; the pure-Python half,
// vkmesh/__init__.py, holds the data classes and the dataset iteration). Bindings over the C++ API with no
// reconstruction code of their own: vkmesh::Reconstructor (api/reconstructor.h) fuses and meshes, the dataset
// reader (io/dataset.h) reads sequences, io/ply.h reads and writes meshes, synth/ writes synthetic sequences.
// What is here: numpy arrays checked and converted, with the dataset reader's own conversion (uint16 depth to
// metres) and checks (intrinsics, rigid poses), so that the same frames give the CLI's floats and messages.
//
// Errors: a bad argument (dtype, shape, value, a non-rigid pose) raises ValueError with vkmesh's message;
// whatever vkmesh::Error reports (Vulkan, capacities that do not fit the device, files) raises vkmesh.Error,
// a RuntimeError. The GIL is released while images are converted and while the GPU works; each Reconstructor
// has a mutex so that its C++ object is used by one thread at a time, as api/reconstructor.h requires.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/exported_mesh.h"
#include "api/reconstructor.h"
#include "api/run_stats_json.h"
#include "core/mesh_delta.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "io/dataset.h"
#include "io/parsers.h"
#include "io/mesh_file.h"
#include "io/mesh_simplify.h"
#include "io/ply.h"
#include "slam/loop_closer.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "vk/context.h"
#ifdef VKMESH_HAVE_VIEWER
#include "viewer/viewer_server.h"
#endif

namespace py = pybind11;
using namespace pybind11::literals;

namespace vkmesh::python {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------
// numpy helpers

// The shape as Python prints it, "(480, 640)", for messages.
std::string shapeOf(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeOf(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

// A float setting as Python shows it: the shortest decimal that reads back as the same float (0.03, where the
// CLI's --stats JSON prints the float's exact value, 0.029999999329447746). Converting it back gives `v` exactly.
double shortest(float v) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof(text), v).ptr;
    double out = v;
    std::from_chars(text, end, out);
    return out;
}

// Any array-like as a numpy array (lists become arrays, whose dtype the caller then checks).
py::array asArray(const py::handle& x) {
    if (py::isinstance<py::array>(x)) return py::reinterpret_borrow<py::array>(x);
    return py::module_::import("numpy").attr("asarray")(x);
}

// A C-contiguous array: arrays that are not (a slice, a transposed view) are copied once.
py::array contiguous(py::array a) {
    if (a.flags() & py::array::c_style) return a;
    return py::module_::import("numpy").attr("ascontiguousarray")(a);
}

template <class T>
bool hasDtype(const py::array& a) {
    return a.dtype().equal(py::dtype::of<T>());
}

// A std::vector handed to numpy without a copy: the array owns the vector through a capsule. V is a plain
// aggregate of `components` T's (float for Eigen::Vector3f, uint32_t for std::array<uint32_t, 3>, ...).
template <class T, class V>
py::array_t<T> moveToArray(std::vector<V>&& values, size_t components) {
    static_assert(sizeof(V) % sizeof(T) == 0, "V must be made of T's");
    std::vector<py::ssize_t> shape{py::ssize_t(values.size())};
    if (components > 1) shape.push_back(py::ssize_t(components));
    if (values.empty()) return py::array_t<T>(shape);
    auto* owner = new std::vector<V>(std::move(values));
    py::capsule free(owner, [](void* p) { delete static_cast<std::vector<V>*>(p); });
    return py::array_t<T>(shape, reinterpret_cast<const T*>(owner->data()), free);
}
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions are handed to numpy as float32 (N, 3)");

// ---------------------------------------------------------------------------------------------------
// Frame inputs: depth, colour, intrinsics, pose

// A depth image as given: uint16 raw units (with a depth scale) or float32 metres, H x W, C-contiguous.
struct DepthInput {
    py::array array;
    bool raw = false;   // uint16
    int width = 0, height = 0;
};

DepthInput checkDepth(const py::handle& object) {
    DepthInput d;
    d.array = asArray(object);
    d.raw = hasDtype<uint16_t>(d.array);
    if (!d.raw && !hasDtype<float>(d.array))
        throw py::value_error("depth must be a uint16 array (raw sensor units, with depth_scale) or a float32 array (metres), "
                              "got dtype " + dtypeOf(d.array) + "; convert with depth.astype(numpy.float32) for metres");
    if (d.array.ndim() != 2)
        throw py::value_error("depth must be an H x W array, got shape " + shapeOf(d.array));
    if (d.array.shape(0) < 1 || d.array.shape(1) < 1 || d.array.shape(0) > 65535 || d.array.shape(1) > 65535)
        throw py::value_error("depth has shape " + shapeOf(d.array) + "; height and width must be in [1, 65535]");
    d.height = int(d.array.shape(0));
    d.width = int(d.array.shape(1));
    d.array = contiguous(d.array);
    return d;
}

// Metres for the GPU, into `out` (its buffer reused from frame to frame). uint16: the dataset reader's own
// conversion (io::rawDepthToMeters), so the same PNG gives the same floats as `vkmesh fuse`. float32: NaN and 0
// mean no measurement; beyond maxDepth becomes 0, as the reader does. Runs without the GIL.
void convertDepth(const DepthInput& d, double depthScale, float maxDepth, DepthImage& out) {
    if (d.raw) {
        io::rawDepthToMeters(static_cast<const uint16_t*>(d.array.data()), d.width, d.height, size_t(d.width), depthScale,
                             std::nullopt, maxDepth, out);
        return;
    }
    out.width = d.width;
    out.height = d.height;
    out.meters.resize(size_t(d.width) * d.height);
    const float* src = static_cast<const float*>(d.array.data());
    for (size_t i = 0; i < out.meters.size(); ++i) {
        float m = src[i];
        if (std::isnan(m)) m = 0.0f;
        if (!(m >= 0.0f && m <= std::numeric_limits<float>::max()))
            throw py::value_error("depth[" + std::to_string(i / d.width) + ", " + std::to_string(i % d.width) + "] = " +
                                  std::to_string(m) + ": depth in metres must be finite and >= 0 (0 or NaN: no measurement)");
        if (maxDepth > 0 && m > maxDepth) m = 0.0f;
        out.meters[i] = m;
    }
}

// A colour image registered to the depth image: uint8 H x W x 3 (red, green, blue), C-contiguous.
std::optional<py::array> checkColor(const py::handle& object, const DepthInput& depth) {
    if (object.is_none()) return std::nullopt;
    py::array c = asArray(object);
    if (!hasDtype<uint8_t>(c))
        throw py::value_error("color must be a uint8 array (H x W x 3, red green blue), got dtype " + dtypeOf(c));
    if (c.ndim() != 3 || c.shape(2) != 3)
        throw py::value_error("color must be an H x W x 3 array (red green blue), got shape " + shapeOf(c) +
                              (c.ndim() == 3 && c.shape(2) == 4 ? "; drop the alpha channel with color[..., :3]" : ""));
    if (c.shape(0) != depth.height || c.shape(1) != depth.width)
        throw py::value_error("color image is " + std::to_string(c.shape(1)) + "x" + std::to_string(c.shape(0)) +
                              " but the depth image is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                              " (colour must be registered to depth)");
    return contiguous(c);
}

void convertColor(const py::array& c, ColorImage& out) {
    out.height = int(c.shape(0));
    out.width = int(c.shape(1));
    out.rgb.resize(size_t(out.width) * out.height * 3);
    std::memcpy(out.rgb.data(), c.data(), out.rgb.size());
}

// (fx, fy, cx, cy) or a 3 x 3 camera matrix, checked as the dataset reader checks --intrinsics.
Intrinsics toIntrinsics(const py::handle& object, int width, int height) {
    py::array a = asArray(object);
    if (!(a.ndim() == 1 && a.shape(0) == 4) && !(a.ndim() == 2 && a.shape(0) == 3 && a.shape(1) == 3))
        throw py::value_error("intrinsics must be (fx, fy, cx, cy) or a 3x3 camera matrix, got shape " + shapeOf(a));
    auto k = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!k) throw py::value_error("intrinsics must be numbers, got dtype " + dtypeOf(a));
    const double* v = k.data();
    Intrinsics out;
    if (a.ndim() == 1) {
        out.fx = float(v[0]), out.fy = float(v[1]), out.cx = float(v[2]), out.cy = float(v[3]);
    } else {
        // A pinhole camera matrix: no skew, last row 0 0 1 (anything else would be silently dropped).
        if (v[1] != 0 || v[3] != 0 || v[6] != 0 || v[7] != 0 || v[8] != 1)
            throw py::value_error("intrinsics: a camera matrix must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
        out.fx = float(v[0]), out.fy = float(v[4]), out.cx = float(v[2]), out.cy = float(v[5]);
    }
    out.width = width;
    out.height = height;
    try {
        checkIntrinsics(out, "intrinsics");
    } catch (const Error& e) {
        throw py::value_error(e.what());
    }
    return out;
}

// A 4 x 4 camera-to-world matrix, checked as the dataset reader checks every pose it reads (validatePose).
py::array poseToPython(const Pose& pose) {
    py::array_t<double> out({py::ssize_t(4), py::ssize_t(4)});
    auto view = out.mutable_unchecked<2>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) view(r, c) = pose(r, c);
    return out;
}

Pose toPose(const py::handle& object, const std::string& where) {
    py::array a = asArray(object);
    if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
        throw py::value_error(where + ": pose must be a 4x4 camera-to-world matrix, got shape " + shapeOf(a));
    auto m = py::array_t<double, py::array::forcecast>::ensure(a);
    if (!m) throw py::value_error(where + ": pose must be numbers, got dtype " + dtypeOf(a));
    auto r = m.unchecked<2>();
    Pose pose;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) pose(i, j) = r(i, j);
    try {
        validatePose(pose, where);
    } catch (const Error& e) {
        throw py::value_error(e.what());
    }
    return pose;
}

py::array_t<double> poseToArray(const Pose& pose) {
    py::array_t<double> out({4, 4});
    auto w = out.mutable_unchecked<2>();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) w(i, j) = pose(i, j);
    return out;
}

// ---------------------------------------------------------------------------------------------------
// Validation messages and capacity warnings

// Validation-layer messages of every Reconstructor, collected after each call (with the GIL held) until
// vkmesh.validation_messages() takes them: the test suite fails on any, as the C++ tests do.
std::vector<std::string>& validationMessages() {
    static std::vector<std::string> messages;
    return messages;
}

void publishMessages(std::vector<std::string>&& messages) {
    auto& all = validationMessages();
    for (auto& m : messages) all.push_back(std::move(m));
}

// A frame's capacity problems (FrameReport::warnings: something did not fit and was skipped; what was fused
// before is kept) as vkmesh.CapacityWarning, which a program can turn into an exception with warnings.simplefilter.
void warnCapacity(const std::vector<std::string>& warnings, uint32_t frame) {
    if (warnings.empty()) return;
    py::object category = py::module_::import("vkmesh._vkmesh").attr("CapacityWarning");
    for (const auto& w : warnings) {
        const std::string text = "frame " + std::to_string(frame) + ": " + w;
        if (PyErr_WarnEx(category.ptr(), text.c_str(), 1) < 0) throw py::error_already_set();
    }
}

// ---------------------------------------------------------------------------------------------------
// Reconstructor

const char* colorModeName(ColorFusion mode) {
    switch (mode) {
        case ColorFusion::Off: return "off";
        case ColorFusion::Average: return "average";
        case ColorFusion::Recent: return "recent";
    }
    return "?";
}

ColorFusion parseColorMode(const std::string& mode) {
    if (mode == "average") return ColorFusion::Average;
    if (mode == "recent") return ColorFusion::Recent;
    if (mode == "off") return ColorFusion::Off;
    throw py::value_error("color_mode '" + mode + "' is not one of 'average', 'recent', 'off'");
}

uint32_t capacity(const char* name, long long value) {
    if (value < 0 || value > 0xFFFFFFFFll)
        throw py::value_error(std::string(name) + " = " + std::to_string(value) + " must be in [0, 2^32)");
    return uint32_t(value);
}

// The capacities of gpu::GpuVolumeConfig, shared by the constructor and load() (initial sizes: they grow).
struct Capacities {
    long long blocks, hashSlots, touched, vertices, chunks, retype, deltaRecords;
    void applyTo(gpu::GpuVolumeConfig& c) const {
        c.blockCapacity = capacity("block_capacity", blocks);
        c.hashCapacity = capacity("hash_capacity", hashSlots);
        c.touchedCapacity = capacity("touched_capacity", touched);
        c.vertexCapacity = capacity("vertex_capacity", vertices);
        c.chunkCapacity = capacity("chunk_capacity", chunks);
        c.retypeCapacity = capacity("retype_capacity", retype);
        c.deltaRecordCapacity = capacity("delta_record_capacity", deltaRecords);
    }
};

vk::ContextOptions deviceOptions(const py::object& device, bool validation) {
    vk::ContextOptions o;
    if (!device.is_none()) {
        if (!py::isinstance<py::int_>(device) || py::isinstance<py::bool_>(device))
            throw py::value_error("device must be None (the first suitable one) or an index from vkmesh.devices(), got " +
                                  py::repr(device).cast<std::string>());
        const long long index = device.cast<long long>();
        if (index < 0) throw py::value_error("device " + std::to_string(index) + " must be >= 0");
        o.deviceIndex = int(std::min<long long>(index, std::numeric_limits<int>::max()));   // too large: vk::Context says so
    }
    o.validation = validation;   // VKMESH_VALIDATION=1 turns it on as well (vk::Context, as for the CLI)
    return o;
}

// Checks a configuration's settings before any device exists: a bad value is a ValueError naming it. The
// image size is not known before the first frame; a placeholder stands in for it.
void checkConfig(gpu::GpuVolumeConfig config) {
    config.imageWidth = config.imageHeight = 1;
    try {
        gpu::resolveConfig(config);
    } catch (const Error& e) {
        throw py::value_error(e.what());
    }
}

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
                         double depthScale, const py::object& colorObject) {
        // Arguments first, with the GIL: nothing reaches the GPU unless all of them are right.
        const DepthInput depth = checkDepth(depthObject);
        const Intrinsics intrinsics = toIntrinsics(intrinsicsObject, depth.width, depth.height);
        const std::optional<Pose> pose = poseObject.is_none() ? std::nullopt : std::optional<Pose>(toPose(poseObject, "integrate()"));
        const std::optional<py::array> color = checkColor(colorObject, depth);
        if (depth.raw && !(std::isfinite(depthScale) && depthScale > 0))
            throw py::value_error("depth_scale " + std::to_string(depthScale) + " must be a positive finite number");
        uint32_t frame = 0;
        std::optional<TrackedFrame> tracked;
        bool fused = true;   // false: a tracked frame that was lost (nothing fused)
        std::vector<std::string> warnings = locked([&](Reconstructor& rec) {
            if (const gpu::GpuVolume* v = rec.volume(); v && (v->config().imageWidth != depth.width || v->config().imageHeight != depth.height))
                throw py::value_error("depth image is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                                      " but the first frame was " + std::to_string(v->config().imageWidth) + "x" +
                                      std::to_string(v->config().imageHeight) + ": every frame must have the first one's size");
            convertDepth(depth, depthScale, maxDepth(rec), depth_);
            if (color) convertColor(*color, color_);
            const auto t0 = std::chrono::steady_clock::now();
            if (pose) {
                lastReport_ = rec.integrate(depth_, color ? &color_ : nullptr, intrinsics, *pose);
            } else {
                tracked = rec.integrate(depth_, color ? &color_ : nullptr, intrinsics);
                fused = tracked->fused.has_value();
                lastReport_ = fused ? std::move(*tracked->fused) : gpu::FrameReport{};
                tracked->fused.reset();
            }
            lastCppSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            lastReport_.delta = MeshDelta{};   // the Reconstructor keeps it (lastDelta); one copy is enough
            frame = rec.framesIntegrated();
#ifdef VKMESH_HAVE_VIEWER
            if (server_ && fused) {
                // Posted to the server's own thread (a copy of the delta): a slow page never holds integrate() up.
                const Pose used = tracked ? tracked->cameraToWorld : *pose;
                Intrinsics camera = intrinsics;
                camera.width = depth.width, camera.height = depth.height;
                server_->publish(rec.lastDelta(), viewer::fusedFrameInfo(frame, 0, lastCppSeconds_ * 1000, lastReport_.counters.blocksInUse, used, camera));
            }
#endif
            return lastReport_.warnings;
        });
        warnCapacity(warnings, frame);
        if (!tracked) return py::none();
        const gpu::TrackingReport& t = tracked->tracking;
        return py::dict("pose"_a = poseToPython(tracked->cameraToWorld), "tracked"_a = t.tracked, "lost_reason"_a = t.lostReason,
                        "iterations"_a = t.iterations, "inliers"_a = t.inliers, "valid_pixels"_a = t.validPixels, "rmse"_a = t.rmse,
                        "ms"_a = t.milliseconds, "model_drawn"_a = t.modelDrawn, "relocalised"_a = tracked->relocalised,
                        "relocalisation_candidates_tried"_a = tracked->relocalisationCandidatesTried,
                        "loop_corrections"_a = tracked->loopCorrections);
    }

    // New poses for fused frames (Reconstructor::correct): indices (N,) and poses (N, 4, 4), all checked first.
    void correct(const py::object& framesObject, const py::object& posesObject) {
        py::array framesArray = asArray(framesObject), posesArray = asArray(posesObject);
        if (framesArray.ndim() != 1) throw py::value_error("correct(): frames must be a 1-D array of frame indices, got shape " + shapeOf(framesArray));
        if (posesArray.ndim() != 3 || posesArray.shape(1) != 4 || posesArray.shape(2) != 4 || posesArray.shape(0) != framesArray.shape(0))
            throw py::value_error("correct(): poses must be an N x 4 x 4 array, one per frame index (" + std::to_string(framesArray.shape(0)) +
                                  "), got shape " + shapeOf(posesArray));
        auto indices = py::array_t<long long, py::array::forcecast>::ensure(framesArray);
        if (!indices) throw py::value_error("correct(): frames must be integers, got dtype " + dtypeOf(framesArray));
        std::vector<uint32_t> frames;
        std::vector<Pose> poses;
        for (py::ssize_t i = 0; i < framesArray.shape(0); ++i) {
            const long long f = indices.at(i);
            if (f < 0 || f > 0xFFFFFFFFll) throw py::value_error("correct(): frame index " + std::to_string(f) + " is out of range");
            frames.push_back(uint32_t(f));
            poses.push_back(toPose(posesArray[py::int_(i)], "correct(): pose " + std::to_string(i) + " (frame " + std::to_string(f) + ")"));
        }
        locked([&](Reconstructor& rec) { rec.correct(frames, poses); });
    }

    size_t pendingCorrections() {
        return locked([](Reconstructor& rec) { return rec.pendingCorrections(); });
    }

    py::dict finishCorrections() {
        gpu::CorrectionReport r = locked([](Reconstructor& rec) { return rec.finishCorrections(); });
        return correctionDict(r);
    }

    py::dict lastCorrections() {
        gpu::CorrectionReport r = locked([](Reconstructor& rec) { return rec.lastCorrections(); });
        return correctionDict(r);
    }

    static py::dict correctionDict(const gpu::CorrectionReport& r) {
        return py::dict("frames_refused"_a = r.framesRefused, "frames"_a = r.frames, "blocks_freed"_a = r.blocksFreed,
                        "observations_dropped"_a = r.observationsDropped, "ms"_a = r.milliseconds, "warnings"_a = r.warnings);
    }

    // Every frame's camera-to-world pose so far (given, tracked, or predicted for a lost frame): N x 4 x 4.
    py::array trajectory() {
        std::vector<Pose> poses = locked([](Reconstructor& rec) { return rec.trajectory(); });
        py::array_t<double> out({py::ssize_t(poses.size()), py::ssize_t(4), py::ssize_t(4)});
        auto view = out.mutable_unchecked<3>();
        for (size_t i = 0; i < poses.size(); ++i)
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) view(py::ssize_t(i), r, c) = poses[i](r, c);
        return out;
    }

    py::object mesh() {
        Mesh m = locked([](Reconstructor& rec) {
            const gpu::ExportedMesh exported = rec.downloadMesh();
            // Ages in the GPU's frame numbers, as `vkmesh fuse` writes them.
            return toMesh(exported, rec.volume() ? rec.volume()->frameNumber() : 0u);
        });
        return meshToPython(std::move(m));
    }

    py::object deltas() {
        MeshDelta delta = locked([&](Reconstructor& rec) {
            if (!options_.trackDeltas)
                throw Error("mesh deltas are not tracked: create the Reconstructor with track_deltas=True");
            return rec.lastDelta();
        });
        const size_t nv = delta.vertices.size(), nt = delta.triangles.size();
        py::array_t<uint32_t> vertexIds(nv), triangleIds(nt), created(nv);
        py::array_t<uint8_t> vertexKinds(nv), triangleKinds(nt), colors({nv, size_t(4)});
        py::array_t<float> positions({nv, size_t(3)}), normals({nv, size_t(3)});
        py::array_t<uint32_t> triangleVertices({nt, size_t(3)});
        for (size_t i = 0; i < nv; ++i) {
            const gpu::DeltaVertexRecord& r = delta.vertices[i];
            vertexIds.mutable_at(i) = deltaId(r.idKind);
            vertexKinds.mutable_at(i) = uint8_t(deltaKind(r.idKind));
            positions.mutable_at(i, 0) = r.px, positions.mutable_at(i, 1) = r.py, positions.mutable_at(i, 2) = r.pz;
            normals.mutable_at(i, 0) = r.nx, normals.mutable_at(i, 1) = r.ny, normals.mutable_at(i, 2) = r.nz;
            created.mutable_at(i) = r.createdFrame;
            for (int c = 0; c < 4; ++c) colors.mutable_at(i, c) = uint8_t(r.color >> (8 * c));
        }
        for (size_t i = 0; i < nt; ++i) {
            const gpu::DeltaTriangleRecord& r = delta.triangles[i];
            triangleIds.mutable_at(i) = deltaId(r.idKind);
            triangleKinds.mutable_at(i) = uint8_t(deltaKind(r.idKind));
            triangleVertices.mutable_at(i, 0) = r.v0, triangleVertices.mutable_at(i, 1) = r.v1, triangleVertices.mutable_at(i, 2) = r.v2;
        }
        return py::module_::import("vkmesh").attr("MeshDelta")(
            "frame"_a = delta.frame, "vertex_ids"_a = vertexIds, "vertex_kinds"_a = vertexKinds, "vertex_positions"_a = positions,
            "vertex_normals"_a = normals, "vertex_created_frames"_a = created, "vertex_colors"_a = colors,
            "triangle_ids"_a = triangleIds, "triangle_kinds"_a = triangleKinds, "triangle_vertices"_a = triangleVertices);
    }

    // The library's run statistics (api/run_stats_json.h: the keys of `vkmesh fuse --stats`), with this module's own
    // keys as they have always been (the settings as Python shows floats, the last frame); where both have a key,
    // this module's value stays, so that no key a script reads changes.
    py::dict stats() {
        struct Snapshot {
            std::string device;
            bool int64Atomics = false, validation = false, hasVolume = false;
            gpu::GpuVolumeConfig config;
            gpu::Counters counters{};
            std::vector<gpu::PoolInfo> pools;
            uint32_t frames = 0;
            gpu::FrameReport last;
            std::optional<FrameStoreStats> store;   // keep_frames
            size_t pendingCorrections = 0;
            std::string run;   // runStatsJson, as JSON text
        };
        Snapshot s = locked([&](Reconstructor& rec) {
            Snapshot s;
            s.device = rec.context().info().name;
            s.int64Atomics = rec.context().int64Atomics();
            s.validation = rec.context().validationEnabled();
            // Before the first frame: the settings with their defaults filled in (hash slots, ...), as the volume will have them.
            s.config = options_.volume;
            s.config.imageWidth = s.config.imageHeight = 1;
            s.config = gpu::resolveConfig(s.config);
            if (const gpu::GpuVolume* v = rec.volume()) {
                s.hasVolume = true;
                s.config = v->config();
                s.counters = v->readCounters();
                s.pools = v->pools();
            }
            s.frames = rec.framesIntegrated();
            s.last = lastReport_;
            if (const FrameStore* store = rec.frameStore()) s.store = store->stats();
            s.pendingCorrections = rec.pendingCorrections();
            s.run = runStatsJson(rec.mapper()).dump();
            return s;
        });
        const gpu::GpuVolumeConfig& c = s.config;
        const gpu::Counters& k = s.counters;
        py::dict d;
        d["device"] = s.device;
        d["int64_atomics"] = s.int64Atomics;
        d["validation"] = s.validation;
        d["frames"] = py::dict("integrated"_a = s.frames);
        d["voxel_size"] = shortest(c.params.voxelSize);
        d["truncation_m"] = shortest(c.params.truncation());
        d["allocation_stride"] = c.params.allocationStride;
        d["allocation_tiles"] = c.params.allocationTiles;
        d["max_depth"] = shortest(c.params.maxDepth);
        d["refine"] = c.refine;
        d["lock_free"] = c.lockFree;
        d["track_deltas"] = options_.trackDeltas;
        d["tracking"] = py::dict("color_weight"_a = shortest(options_.tracker.colorWeight),
                                 "solve"_a = options_.tracker.solveOnGpu ? "gpu" : "host", "downsample"_a = options_.tracker.downsample,
                                 "model_reuse"_a = options_.tracker.modelReuseFrames);
        d["color"] = py::dict("fused"_a = c.params.colorFusion != ColorFusion::Off, "mode"_a = colorModeName(c.params.colorFusion),
                              "recency"_a = shortest(c.params.colorRecency));
        if (s.store) {
            const FrameStoreStats& fs = *s.store;
            d["frame_store"] = py::dict("frames"_a = fs.frames, "frames_spilled"_a = fs.framesSpilled, "raw_bytes"_a = fs.rawBytes,
                                        "compressed_bytes"_a = fs.compressedBytes, "bytes_in_memory"_a = fs.bytesInMemory,
                                        "bytes_on_disk"_a = fs.bytesOnDisk,
                                        "bytes_per_frame"_a = fs.frames ? double(fs.compressedBytes) / double(fs.frames) : 0.0,
                                        "pending_corrections"_a = s.pendingCorrections);
        }
        d["recycling"] = py::dict("keep_radius"_a = shortest(c.keepRadius), "recycle"_a = c.recycle,
                                  "recycle_after_frames"_a = c.recycleAfterFrames, "starve_weight"_a = shortest(c.starveWeight));
        d["capacities"] = py::dict("grow"_a = c.growCapacities, "blocks"_a = c.blockCapacity, "hash_slots"_a = c.hashCapacity,
                                   "touched"_a = c.touchedCapacity, "retype"_a = c.retypeCapacity, "vertices"_a = c.vertexCapacity,
                                   "triangle_chunks"_a = c.chunkCapacity);
        if (!s.hasVolume) return withRunStats(d, s.run);   // nothing on the GPU before the first frame
        d["blocks"] = py::dict("in_use"_a = k.blocksInUse, "capacity"_a = c.blockCapacity, "hash_capacity"_a = c.hashCapacity,
                               "hash_entries"_a = k.hashEntries, "hash_tombstones"_a = k.hashTombstones);
        d["heaps"] = py::dict(
            "vertices"_a = py::dict("capacity"_a = c.vertexCapacity, "live"_a = k.verticesInUse, "free"_a = k.vertexFreeTop,
                                    "high_water"_a = k.vertexHighWater),
            "triangle_chunks"_a = py::dict("capacity"_a = c.chunkCapacity, "live"_a = k.chunksInUse, "free"_a = k.chunkFreeTop,
                                           "high_water"_a = k.chunkHighWater),
            "live_triangles"_a = k.liveTriangles);
        py::dict pools;
        size_t total = 0;
        for (const auto& p : s.pools) pools[py::str(p.name)] = p.bytes, total += p.bytes;
        d["gpu_pool_bytes"] = pools;
        d["gpu_bytes_total"] = total;
        py::dict gpuMs;
        for (const auto& [name, ms] : s.last.stageMs) gpuMs[py::str(name)] = ms;
        const gpu::Counters& f = s.last.counters;
        d["last_frame"] = py::dict("gpu_ms"_a = gpuMs, "touched_blocks"_a = f.touchedCount, "dirty_blocks"_a = f.dirtyCount,
                                   "cubes_retyped"_a = f.cubesRetyped, "triangles_created"_a = f.trianglesCreated,
                                   "warnings"_a = s.last.warnings, "growth"_a = s.last.growth,
                                   "deferred_attempts"_a = s.last.deferredAttempts);
        return withRunStats(d, s.run);
    }

    // `own` with every key of the run statistics it lacks, at any depth (json.loads of `runJson`).
    static py::dict withRunStats(py::dict own, const std::string& runJson) {
        const py::dict run = py::module_::import("json").attr("loads")(runJson);
        addMissing(own, run);
        return own;
    }
    static void addMissing(py::dict& into, const py::dict& from) {
        for (const auto& [key, value] : from) {
            if (!into.contains(key)) {
                into[key] = value;
            } else if (py::isinstance<py::dict>(into[key]) && py::isinstance<py::dict>(value)) {
                py::dict inner = into[key];
                addMissing(inner, value.cast<py::dict>());
            }
        }
    }

    void save(const fs::path& path) {
        locked([&](Reconstructor& rec) { rec.save(path); });
    }

    void close() {
        py::gil_scoped_release release;
        std::lock_guard<std::mutex> lock(mutex_);
#ifdef VKMESH_HAVE_VIEWER
        server_.reset();
#endif
        rec_.reset();
    }

    // The live browser viewer (docs/VIEWER.md) on a server thread of its own, fed each frame's delta by integrate().
    std::string serve(int port, const std::string& host) {
#ifdef VKMESH_HAVE_VIEWER
        if (port < 0 || port > 65535) throw py::value_error("port " + std::to_string(port) + " must be in 0..65535 (0: any free port)");
        return locked([&](Reconstructor& rec) {
            if (server_) throw Error("this Reconstructor already serves the viewer at " + server_->url() + " (stop_serving() first)");
            if (!options_.trackDeltas)
                throw Error("serve() needs the mesh deltas: create the Reconstructor with track_deltas=True");
            // A page must be able to build the mesh from deltas alone, so it must see every frame from the first.
            if (rec.framesIntegrated() > 0)
                throw Error("serve() must be called before the first integrate() (" + std::to_string(rec.framesIntegrated()) +
                            " frames are already fused, and a page builds the mesh from every frame's changes)");
            viewer::ServerOptions o;
            o.host = host;
            o.port = uint16_t(port);
            o.quiet = true;
            server_.emplace(o);
            return server_->url();
        });
#else
        (void)port, (void)host;
        throw Error("this vkmesh module was built without the browser viewer (it needs libboost-dev and libjs-three at build time)");
#endif
    }

    py::dict stopServing() {
        py::dict d;
#ifdef VKMESH_HAVE_VIEWER
        std::optional<viewer::ServerStats> stats = locked([&](Reconstructor&) -> std::optional<viewer::ServerStats> {
            if (!server_) return std::nullopt;
            server_->stop();
            viewer::ServerStats s = server_->stats();
            server_.reset();
            return s;
        });
        if (stats) {
            d["pages"] = stats->pagesConnected;
            d["messages_sent"] = stats->messagesSent;
            d["bytes_sent"] = stats->bytesSent;
            d["frames_published"] = stats->framesPublished;
            d["frames_coalesced"] = stats->framesCoalesced;
        }
#endif
        return d;
    }
    bool closed() {
        std::lock_guard<std::mutex> lock(mutex_);
        return !rec_;
    }
    uint32_t framesIntegrated() {
        return locked([](Reconstructor& rec) { return rec.framesIntegrated(); });
    }
    std::string repr() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!rec_) return "<vkmesh.Reconstructor (closed)>";
        const gpu::GpuVolume* v = rec_->volume();
        const VolumeParams& p = v ? v->config().params : options_.volume.params;
        char voxel[32];
        std::snprintf(voxel, sizeof(voxel), "%g", p.voxelSize);
        return "<vkmesh.Reconstructor voxel " + std::string(voxel) + " m, " + std::to_string(rec_->framesIntegrated()) +
               " frames, on " + rec_->context().info().name + ">";
    }

    // For the overhead benchmark (bench/python_overhead.py): how long the last integrate() spent in the C++ API's
    // Reconstructor::integrate; the rest of its wall time is the module's.
    double lastCppSeconds() {
        std::lock_guard<std::mutex> lock(mutex_);
        return lastCppSeconds_;
    }

    // For the overhead benchmark: the C++ API's integrate on a frame converted beforehand, timed in C++.
    double timedCppIntegrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& pose) {
        return locked([&](Reconstructor& rec) {
            const auto t0 = std::chrono::steady_clock::now();
            rec.integrate(depth, color, intrinsics, pose);
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        });
    }

    static py::object meshToPython(Mesh&& m) {
        py::object normals = m.normals.empty() ? py::object(py::none()) : py::object(moveToArray<float>(std::move(m.normals), 3));
        py::object colors = m.colors.empty() ? py::object(py::none()) : py::object(moveToArray<uint8_t>(std::move(m.colors), 3));
        py::object ages = m.vertexAge.empty() ? py::object(py::none()) : py::object(moveToArray<uint32_t>(std::move(m.vertexAge), 1));
        return py::module_::import("vkmesh").attr("Mesh")(moveToArray<float>(std::move(m.positions), 3),
                                                          moveToArray<uint32_t>(std::move(m.triangles), 3), "normals"_a = normals,
                                                          "colors"_a = colors, "ages"_a = ages);
    }

private:
    // Depth beyond this is no measurement (the volume's max depth: the constructor's, or a loaded map's).
    float maxDepth(Reconstructor& rec) const {
        return rec.volume() ? rec.volume()->config().params.maxDepth : options_.volume.params.maxDepth;
    }

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

// keep_frames, corrections_per_frame, frames_budget_mb, frames_spill (ReconstructorOptions, docs/CORRECTION.md), and
// loop_closure (docs/LOOP_CLOSURE.md: its loop closer is made once the tracker's options are known, withLoopClosure).
struct CorrectionSettings {
    bool keepFrames = false;
    bool loopClosure = false;
    long long correctionsPerFrame = ReconstructorOptions{}.correctionsPerFrame;
    double framesBudgetMb = 1024;
    std::string framesSpill;
    void applyTo(ReconstructorOptions& o) const {
        if (correctionsPerFrame < 0 || correctionsPerFrame > 1000000)
            throw py::value_error("corrections_per_frame " + std::to_string(correctionsPerFrame) + " must be in [0, 1000000]");
        if (!(framesBudgetMb > 0)) throw py::value_error("frames_budget_mb " + std::to_string(framesBudgetMb) + " must be positive");
        o.keepFrames = keepFrames;
        o.correctionsPerFrame = uint32_t(correctionsPerFrame);
        o.frameStore.memoryBudgetBytes = size_t(framesBudgetMb * 1024 * 1024);
        o.frameStore.spillFolder = framesSpill;
    }
    void withLoopClosure(ReconstructorOptions& o) const {
        if (!loopClosure) return;
        if (!keepFrames) throw py::value_error("loop_closure=True re-fuses the frames a loop moves: it needs keep_frames=True");
        slam::LoopClosureOptions lo;
        lo.tracker = o.tracker;
        o.loopClosure = std::make_shared<slam::LoopCloser>(lo);
    }
};

std::unique_ptr<PyReconstructor> makeReconstructor(float voxelSize, float truncationVoxels, float maxDepth, const py::object& device,
                                                   const std::string& colorMode, float colorRecency, bool trackDeltas, float maxWeight,
                                                   float minWeight, int allocationStride, bool refine, float refineEpsilonVoxels,
                                                   bool lockFree, const Capacities& capacities, bool growCapacities, float keepRadius,
                                                   bool recycle, long long recycleAfterFrames, float starveWeight, bool validation,
                                                   float trackColorWeight, const std::string& trackSolve, int trackDownsample,
                                                   int trackModelReuse, const CorrectionSettings& correction, bool allocationTiles) {
    ReconstructorOptions o;
    correction.applyTo(o);
    gpu::GpuVolumeConfig& c = o.volume;
    c.params.voxelSize = voxelSize;
    c.params.truncVoxels = truncationVoxels;
    c.params.maxDepth = maxDepth;
    c.params.maxWeight = maxWeight;
    if (maxWeight != VolumeParams{}.maxWeight)
        PyErr_WarnEx(PyExc_DeprecationWarning, "max_weight is deprecated and has no effect: the TSDF keeps exact sums so that frames can be taken out again", 1);
    c.params.allocationStride = allocationStride;
    c.params.allocationTiles = allocationTiles;
    c.params.colorFusion = parseColorMode(colorMode);
    c.params.colorRecency = colorRecency;
    c.minMeshWeight = minWeight;
    c.refine = refine;
    c.refineEpsilonVoxels = refineEpsilonVoxels;
    c.lockFree = lockFree;
    capacities.applyTo(c);
    c.growCapacities = growCapacities;
    c.keepRadius = keepRadius;
    c.recycle = recycle;
    c.recycleAfterFrames = capacity("recycle_after_frames", recycleAfterFrames);
    c.starveWeight = starveWeight;
    // The checks `vkmesh fuse` makes on its options (CLI11 ranges) that the volume itself does not.
    if (!(minWeight >= 1.0f && minWeight <= 255.0f)) throw py::value_error("min_weight " + std::to_string(minWeight) + " must be in [1, 255]");
    if (c.blockCapacity == 0) throw py::value_error("block_capacity must be at least 1");
    checkConfig(c);
    if (!(trackColorWeight >= 0.0f && trackColorWeight <= 100.0f))
        throw py::value_error("track_color_weight " + std::to_string(trackColorWeight) + " must be in [0, 100]");
    if (trackSolve != "host" && trackSolve != "gpu") throw py::value_error("track_solve '" + trackSolve + "' must be 'host' or 'gpu'");
    o.tracker.colorWeight = trackColorWeight;
    o.tracker.solveOnGpu = trackSolve == "gpu";
    if (trackDownsample != 0 && trackDownsample != 1 && trackDownsample != 2 && trackDownsample != 4)
        throw py::value_error("track_downsample " + std::to_string(trackDownsample) + " must be 0 (by the frame's width), 1, 2 or 4");
    o.tracker.downsample = trackDownsample;
    if (trackModelReuse < 0 || trackModelReuse > 1000)
        throw py::value_error("track_model_reuse " + std::to_string(trackModelReuse) + " must be in 0..1000");
    o.tracker.modelReuseFrames = trackModelReuse;
    correction.withLoopClosure(o);
    o.trackDeltas = trackDeltas;
    o.device = deviceOptions(device, validation);
    std::unique_ptr<Reconstructor> rec;
    std::vector<std::string> messages;
    {
        py::gil_scoped_release release;   // creating the instance and the device takes a while
        rec = std::make_unique<Reconstructor>(o);
        messages = rec->context().takeValidationMessages();
    }
    publishMessages(std::move(messages));
    return std::make_unique<PyReconstructor>(o, std::move(rec));
}

std::unique_ptr<PyReconstructor> loadReconstructor(const fs::path& path, const py::object& device, bool trackDeltas,
                                                   const Capacities& capacities, bool validation, const CorrectionSettings& correction) {
    ReconstructorOptions o;
    correction.applyTo(o);
    capacities.applyTo(o.volume);
    o.trackDeltas = trackDeltas;
    o.device = deviceOptions(device, validation);
    std::unique_ptr<Reconstructor> rec;
    std::vector<std::string> messages;
    {
        py::gil_scoped_release release;
        rec = Reconstructor::load(path, o);
        messages = rec->context().takeValidationMessages();
    }
    publishMessages(std::move(messages));
    o.volume = rec->volume()->config();   // the map's settings (voxel size, max depth, colour, ...)
    return std::make_unique<PyReconstructor>(o, std::move(rec));
}

// A frame converted to the C++ API's types ahead of time, for the overhead benchmark (bench/python_overhead.py).
struct CppFrame {
    DepthImage depth;
    std::optional<ColorImage> color;
    Intrinsics intrinsics;
    Pose pose;
};

// ---------------------------------------------------------------------------------------------------
// Dataset

class PyDataset {
public:
    explicit PyDataset(std::unique_ptr<Dataset> ds) : ds_(std::move(ds)) {}
    const Dataset& get() const { return *ds_; }

    // Frame i: depth in metres (the reader's conversion, with its max depth), colour or None, pose, paths. A
    // colour image that cannot be used is reported in "color_warning" (the frame has no colour then).
    py::dict load(size_t i) const {
        DepthImage depth;
        ColorImage color;
        std::string colorWarning;
        {
            py::gil_scoped_release release;   // PNG/JPEG decoding; the reader is const and stateless
            depth = ds_->loadDepth(i);
            color = ds_->loadColor(i, &colorWarning, &depth);
        }
        const FrameInfo& f = ds_->frame(i);
        py::array d = moveToArray<float>(std::move(depth.meters), 1).reshape({depth.height, depth.width});
        py::object c = py::none();
        if (!color.empty()) c = moveToArray<uint8_t>(std::move(color.rgb), 1).reshape({color.height, color.width, 3});
        return py::dict("index"_a = f.index, "timestamp"_a = f.timestamp, "depth"_a = d, "color"_a = c,
                        "color_warning"_a = colorWarning,
                        "pose"_a = f.hasPose ? py::object(poseToArray(f.cameraToWorld)) : py::object(py::none()),
                        "depth_path"_a = f.depthPath.string(), "color_path"_a = f.colorPath.string());
    }

private:
    std::unique_ptr<Dataset> ds_;
};

// ---------------------------------------------------------------------------------------------------
// Meshes on disk

Mesh meshFromArrays(const py::array& vertices, const py::array& triangles, const py::object& normals, const py::object& colors,
                    const py::object& ages) {
    // vkmesh.Mesh has checked the dtypes and shapes; checked again here, where the memory is read.
    auto expect = [](const py::array& a, bool dtypeOk, py::ssize_t n, int columns, const char* what) {
        if (!dtypeOk || a.ndim() != (columns > 1 ? 2 : 1) || (n >= 0 && a.shape(0) != n) || (columns > 1 && a.shape(1) != columns))
            throw py::value_error(std::string(what) + " has dtype " + dtypeOf(a) + " and shape " + shapeOf(a));
    };
    const py::array v = contiguous(vertices), t = contiguous(triangles);
    expect(v, hasDtype<float>(v), -1, 3, "vertices");
    expect(t, hasDtype<uint32_t>(t), -1, 3, "triangles");
    const size_t n = size_t(v.shape(0));
    auto vectors = [](const py::array& a, std::vector<Eigen::Vector3f>& out) {
        const float* p = static_cast<const float*>(a.data());
        out.resize(size_t(a.shape(0)));
        for (size_t i = 0; i < out.size(); ++i) out[i] = Eigen::Vector3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    };
    Mesh m;
    vectors(v, m.positions);
    m.triangles.resize(size_t(t.shape(0)));
    std::memcpy(m.triangles.data(), t.data(), m.triangles.size() * 3 * sizeof(uint32_t));
    if (!normals.is_none()) {
        const py::array a = contiguous(asArray(normals));
        expect(a, hasDtype<float>(a), py::ssize_t(n), 3, "normals");
        vectors(a, m.normals);
    }
    if (!colors.is_none()) {
        const py::array a = contiguous(asArray(colors));
        expect(a, hasDtype<uint8_t>(a), py::ssize_t(n), 3, "colors");
        m.colors.resize(n);
        std::memcpy(m.colors.data(), a.data(), n * 3);
    }
    if (!ages.is_none()) {
        const py::array a = contiguous(asArray(ages));
        expect(a, hasDtype<uint32_t>(a), py::ssize_t(n), 1, "ages");
        m.vertexAge.resize(n);
        std::memcpy(m.vertexAge.data(), a.data(), n * sizeof(uint32_t));
    }
    return m;
}

}  // namespace

}  // namespace vkmesh::python

// =====================================================================================================

PYBIND11_MODULE(_vkmesh, m) {
    using namespace vkmesh;
    using namespace vkmesh::python;
    m.doc() = "The compiled part of vkmesh (import vkmesh instead; see help(vkmesh)).";

    py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
    m.attr("Error").attr("__doc__") =
        "What vkmesh reports when it cannot do what was asked: no usable Vulkan device, a capacity that does not fit "
        "the device, an unreadable file or dataset, a closed Reconstructor. A RuntimeError; the message names the "
        "device, file or value at fault. (Bad arguments raise ValueError instead.)";
    m.attr("Error").attr("__module__") = "vkmesh";
    m.attr("CapacityWarning") = py::reinterpret_steal<py::object>(
        PyErr_NewExceptionWithDoc("vkmesh.CapacityWarning",
                                  "A frame hit a capacity it could not grow past (a device limit, or grow_capacities=False): "
                                  "what did not fit was skipped, everything fused before is kept. Turn it into an "
                                  "exception with warnings.simplefilter('error', vkmesh.CapacityWarning).",
                                  PyExc_RuntimeWarning, nullptr));

    const gpu::GpuVolumeConfig dc;   // the library's defaults, which are `vkmesh fuse`'s
    const VolumeParams dp;
    py::class_<PyReconstructor>(m, "Reconstructor", R"doc(
Fuses depth frames into a TSDF on the GPU and keeps one incremental triangle mesh up to date.

    r = vkmesh.Reconstructor(voxel_size=0.02)
    for f in vkmesh.open_dataset("room"):
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    m = r.mesh()                  # m.vertices (N, 3) float32, m.triangles (M, 3) uint32, ...
    m.save("room.ply")

The defaults are those of `vkmesh fuse`, so the same frames give the CLI's mesh. Every capacity is an initial
size that grows between frames when nearly full (grow_capacities=True). Runs on the first suitable Vulkan
device unless `device` gives an index from vkmesh.devices(); VKMESH_VALIDATION=1 in the environment (or
validation=True) turns the Khronos validation layer on. One thread at a time uses a Reconstructor (calls from
several threads wait for each other); the GIL is released while the GPU works.

Keyword arguments (all optional):
  voxel_size            metres between TSDF samples (--voxel; 0.03)
  truncation_voxels     truncation distance in voxels (--trunc; 4)
  max_depth             depth beyond this many metres is ignored (--max-depth; 4)
  device                None (a discrete GPU if any, else the first suitable device) or an index (--device)
  color_mode            'average' (running average with the TSDF weights), 'recent' (exponential, follows
                        lighting changes, see color_recency) or 'off' (depth only, 4 bytes per cube less)
  color_recency         'recent': share of the newest colour, in (0, 1] (--color-recency; 0.2)
  track_deltas          keep each frame's mesh changes for deltas() (--deltas)
  max_weight            deprecated, no effect (a DeprecationWarning): the TSDF keeps exact sums (--max-weight)
  min_weight            a cube is meshed when its 8 corners have this weight (--min-weight; 1)
  allocation_stride     allocate blocks from every Nth pixel (--alloc-stride; 2)
  allocation_tiles      claim the blocks around the plane of a tile of 8 x 8 sampled pixels where one fits instead of
                        walking every sampled pixel's band (--alloc-tiles / --alloc-pixels; True)
  refine, refine_epsilon_voxels   Hamming-distance refinement of cube types (--refine, --refine-eps)
  lock_free             the paper's lock-free vertex claims (--lock-free; same mesh)
  block_capacity, hash_capacity, touched_capacity, vertex_capacity, chunk_capacity, retype_capacity,
  delta_record_capacity initial capacities (gpu::GpuVolumeConfig; --blocks, --hash-slots, --vertices, --chunks)
  grow_capacities       grow them when nearly full (True); False: fixed, what does not fit is skipped and
                        reported as a vkmesh.CapacityWarning (--no-grow)
  keep_radius, recycle, recycle_after_frames, starve_weight   bounded maps (--keep-radius, --recycle, ...)
  validation            the Khronos validation layer (also on with VKMESH_VALIDATION=1)
  track_color_weight    tracking (integrate without a pose): the photometric term's weight (--track-color-weight; 0.1)
  track_solve           tracking: 'host' (systems solved in double, a GPU submission per ICP iteration) or 'gpu'
                        (in float; the frame's tracking, fusion and meshing in one submission) (--track-solve; 'host')
  track_downsample      tracking on the frames downsampled by 1, 2 or 4; 0: 2 for frames at least 640 pixels wide,
                        else 1 (--track-downsample; 0)
  track_model_reuse     tracking: frames in a row that may reuse the model maps (the mesh drawn for an earlier frame)
                        while the camera is predicted within 4 cm and 4 degrees of where they were drawn; 0: the
                        mesh is drawn for every frame (--track-model-reuse; 2)
  keep_frames           keep every fused frame (compressed) so that correct() can re-fuse frames whose poses
                        change; save() writes them beside the map (docs/CORRECTION.md; False)
  corrections_per_frame corrected frames re-fused by each later integrate() (2)
  frames_budget_mb, frames_spill   the kept frames' memory budget in MiB (1024) and a folder for those beyond it
                        ('' : none, and a frame beyond the budget raises vkmesh.Error) (--frames-budget, --frames-spill)
  loop_closure          tracking: recognise places seen before, verify them, optimise a pose graph and re-fuse the
                        frames a loop moves; relocalise lost frames from keyframes (docs/LOOP_CLOSURE.md; needs
                        keep_frames=True; --loop-closure; False)

Bad settings raise ValueError; no usable device or a capacity that does not fit it raises vkmesh.Error.
)doc")
        // Float settings are taken as Python floats (doubles) whose defaults read back as the library's floats.
        .def(py::init([](double voxelSize, double truncationVoxels, double maxDepth, const py::object& device, const std::string& colorMode,
                         double colorRecency, bool trackDeltas, double maxWeight, double minWeight, int allocationStride, bool refine,
                         double refineEpsilonVoxels, bool lockFree, long long blockCapacity, long long hashCapacity,
                         long long touchedCapacity, long long vertexCapacity, long long chunkCapacity, long long retypeCapacity,
                         long long deltaRecordCapacity, bool growCapacities, double keepRadius, bool recycle,
                         long long recycleAfterFrames, double starveWeight, bool validation, double trackColorWeight,
                         const std::string& trackSolve, int trackDownsample, int trackModelReuse, bool keepFrames,
                         long long correctionsPerFrame, double framesBudgetMb, const std::string& framesSpill, bool loopClosure,
                         bool allocationTiles) {
                 return makeReconstructor(voxelSize, truncationVoxels, maxDepth, device, colorMode, colorRecency, trackDeltas,
                                          maxWeight, minWeight, allocationStride, refine, refineEpsilonVoxels, lockFree,
                                          {blockCapacity, hashCapacity, touchedCapacity, vertexCapacity, chunkCapacity,
                                           retypeCapacity, deltaRecordCapacity},
                                          growCapacities, keepRadius, recycle, recycleAfterFrames, starveWeight, validation,
                                          float(trackColorWeight), trackSolve, trackDownsample, trackModelReuse,
                                          {keepFrames, loopClosure, correctionsPerFrame, framesBudgetMb, framesSpill}, allocationTiles);
             }),
             py::kw_only(), "voxel_size"_a = shortest(dp.voxelSize), "truncation_voxels"_a = shortest(dp.truncVoxels),
             // `vkmesh fuse --max-depth` defaults to 4 m (host/cli_options.h, DatasetArgs), not VolumeParams' 5 m.
             "max_depth"_a = 4.0, "device"_a = py::none(), "color_mode"_a = "average", "color_recency"_a = shortest(dp.colorRecency),
             "track_deltas"_a = false, "max_weight"_a = shortest(dp.maxWeight), "min_weight"_a = shortest(dc.minMeshWeight),
             "allocation_stride"_a = dp.allocationStride, "refine"_a = dc.refine,
             "refine_epsilon_voxels"_a = shortest(dc.refineEpsilonVoxels),
             "lock_free"_a = dc.lockFree, "block_capacity"_a = dc.blockCapacity, "hash_capacity"_a = dc.hashCapacity,
             "touched_capacity"_a = dc.touchedCapacity, "vertex_capacity"_a = dc.vertexCapacity, "chunk_capacity"_a = dc.chunkCapacity,
             "retype_capacity"_a = dc.retypeCapacity, "delta_record_capacity"_a = dc.deltaRecordCapacity,
             "grow_capacities"_a = dc.growCapacities, "keep_radius"_a = shortest(dc.keepRadius), "recycle"_a = dc.recycle,
             "recycle_after_frames"_a = dc.recycleAfterFrames, "starve_weight"_a = shortest(dc.starveWeight), "validation"_a = false,
             "track_color_weight"_a = shortest(gpu::TrackerOptions{}.colorWeight), "track_solve"_a = "host",
             "track_downsample"_a = gpu::TrackerOptions{}.downsample,
             "track_model_reuse"_a = gpu::TrackerOptions{}.modelReuseFrames, "keep_frames"_a = false,
             "corrections_per_frame"_a = ReconstructorOptions{}.correctionsPerFrame, "frames_budget_mb"_a = 1024.0, "frames_spill"_a = "",
             "loop_closure"_a = false, "allocation_tiles"_a = dp.allocationTiles)
        .def("integrate", &PyReconstructor::integrate, "depth"_a, "intrinsics"_a, "pose"_a = py::none(), "depth_scale"_a = 5000.0,
             "color"_a = py::none(), R"doc(
Fuses one frame and updates the mesh; returns when the GPU has finished it.

depth        H x W numpy array: uint16 raw sensor units (divided by depth_scale, as vkmesh reads a dataset's
             PNGs) or float32 metres (0 or NaN: no measurement). Depth beyond max_depth is ignored. Every
             frame must have the first frame's size. Arrays that are not C-contiguous are copied once.
intrinsics   (fx, fy, cx, cy) in pixels, or a 3x3 camera matrix.
pose         4x4 camera-to-world matrix (the camera's pose in the world), rigid: a rotation and a translation.
             None: the camera is tracked against the mesh fused so far (docs/TRACKING.md); the very first frame
             is fused at the identity (or at the last pose given). Returns then a dict: "pose" (the 4x4 pose
             used), "tracked" (False: the frame was lost and not fused; "pose" is the prediction),
             "lost_reason", "iterations", "inliers", "valid_pixels", "rmse" (metres), "ms". With a pose: None.
depth_scale  raw units per metre for uint16 depth (5000: TUM; 1000: millimetres); ignored for float32.
color        None or an H x W x 3 uint8 array (red, green, blue) registered to the depth image.

Raises ValueError (wrong dtype, shape or value; a pose that is not rigid) before anything reaches the GPU,
vkmesh.Error for Vulkan problems. Capacity problems are vkmesh.CapacityWarning warnings.
)doc")
        .def("correct", &PyReconstructor::correct, "frames"_a, "poses"_a, R"doc(
New camera-to-world poses for frames already fused (docs/CORRECTION.md; needs keep_frames=True): frames is a
1-D array of frame indices (frame i: the i-th frame integrated, trajectory()[i]), poses an N x 4 x 4 array.
Every index and pose is checked first (ValueError for a bad array or pose, vkmesh.Error for a frame that was
not kept, e.g. lost by tracking), and then nothing is queued. Each frame is de-integrated at the pose it was
fused at and integrated at the new one, exactly: the map then equals one fused at the new poses from the start.
The largest pose changes go first, corrections_per_frame of them in each later integrate(); finish_corrections()
does the rest at once. The mesh follows; deltas() reports every change.
)doc")
        .def("pending_corrections", &PyReconstructor::pendingCorrections, "How many corrected frames wait to be re-fused.")
        .def("finish_corrections", &PyReconstructor::finishCorrections, R"doc(
Re-fuses every queued frame now and publishes the mesh. Returns a dict: frames_refused, frames (their indices in
the order re-fused), blocks_freed (blocks left with no observation), observations_dropped (0 for a consistent
map), ms, warnings.
)doc")
        .def("last_corrections", &PyReconstructor::lastCorrections,
             "What the last integrate() or finish_corrections() re-fused (the dict finish_corrections() returns).")
        .def("trajectory", &PyReconstructor::trajectory, R"doc(
Every frame's camera-to-world pose so far (given, tracked, or predicted for a lost frame), as an N x 4 x 4 array.
)doc")
        .def("mesh", &PyReconstructor::mesh, R"doc(
The mesh after the last frame, copied from the GPU: a vkmesh.Mesh with vertices (N, 3) float32, triangles
(M, 3) uint32 (counter-clockwise seen from outside), normals (N, 3) float32, colors (N, 3) uint8 (None when no
colour was fused; grey for vertices no colour reached) and ages (N,) uint32 (frames since each vertex was
created). Empty before the first frame. To save a map that resumes exactly, call save() before mesh().
)doc")
        .def("deltas", &PyReconstructor::deltas, R"doc(
The last frame's mesh changes (docs/DELTAS.md) as a vkmesh.MeshDelta: vertices and triangles added, changed
(vertices only) or removed, by id. Needs track_deltas=True (else vkmesh.Error). Applying every frame's deltas
in order to an empty mesh gives mesh().
)doc")
        .def("stats", &PyReconstructor::stats, R"doc(
Counts, capacities and memory as a dict, with the keys `vkmesh fuse --stats` uses for the same things:
device, int64_atomics, frames, voxel_size, truncation_m, allocation_stride, allocation_tiles, max_depth, color, capacities,
recycling, and after the first frame blocks, heaps, gpu_pool_bytes, gpu_bytes_total and last_frame (its
GPU milliseconds per stage, counts, capacity warnings and growth); with keep_frames, frame_store (frames,
compressed bytes in memory and on disk, bytes_per_frame, pending_corrections).
)doc")
        .def("save", &PyReconstructor::save, "path"_a, R"doc(
Writes everything the reconstruction holds after the last frame to a map file (.vkmap, docs/MAPFILE.md), and with
keep_frames the kept frames beside it (the path with the extension .vkframes, docs/CORRECTION.md).
Reconstructor.load(path), `vkmesh fuse --load path` and `vkmesh export path` continue from it exactly.
Raises vkmesh.Error before the first frame or when the file cannot be written.
)doc")
        .def_static("load", [](const fs::path& path, const py::object& device, bool trackDeltas, long long blockCapacity,
                               long long hashCapacity, long long touchedCapacity, long long vertexCapacity, long long chunkCapacity,
                               long long retypeCapacity, long long deltaRecordCapacity, bool validation, bool keepFrames,
                               long long correctionsPerFrame, double framesBudgetMb, const std::string& framesSpill) {
                        return loadReconstructor(path, device, trackDeltas,
                                                 {blockCapacity, hashCapacity, touchedCapacity, vertexCapacity, chunkCapacity,
                                                  retypeCapacity, deltaRecordCapacity},
                                                 validation, {keepFrames, false, correctionsPerFrame, framesBudgetMb, framesSpill});
                    },
                    "path"_a, py::kw_only(), "device"_a = py::none(), "track_deltas"_a = false, "block_capacity"_a = dc.blockCapacity,
                    "hash_capacity"_a = dc.hashCapacity, "touched_capacity"_a = dc.touchedCapacity,
                    "vertex_capacity"_a = dc.vertexCapacity, "chunk_capacity"_a = dc.chunkCapacity, "retype_capacity"_a = dc.retypeCapacity,
                    "delta_record_capacity"_a = dc.deltaRecordCapacity, "validation"_a = false, "keep_frames"_a = false,
                    "corrections_per_frame"_a = ReconstructorOptions{}.correctionsPerFrame, "frames_budget_mb"_a = 1024.0,
                    "frames_spill"_a = "", R"doc(
A Reconstructor continuing the map in `path` (written by save() or `vkmesh fuse --save`): the next integrate()
gives exactly what an uninterrupted run would have. keep_frames=True also loads the frame store saved beside it
(path with the extension .vkframes), so that correct() works on the map's frames (vkmesh.Error when there is
none, or when it was saved with another map). The map's settings are used (voxel size, truncation, max
depth, colour, ...); the capacities given here where larger than the map's. Raises vkmesh.Error naming the
file and the problem for a missing, corrupt or truncated map.
)doc")
        .def("serve",
             [](PyReconstructor& self, int port, const std::string& host) {
                 const std::string url = self.serve(port, host);
                 py::print("vkmesh: serving the viewer at " + url);
                 return url;
             },
             "port"_a = 8080, "host"_a = "127.0.0.1", R"doc(
Serves the live browser viewer (docs/VIEWER.md) and returns its URL (also printed): every later integrate()
sends the frame's mesh changes to the pages open at that URL, and a page that joins late gets the whole mesh
first. Needs track_deltas=True and must be called before the first integrate(). The server runs on a thread of
its own: integrate() only hands it a copy of the frame's changes and never waits for a page. host 127.0.0.1
(default) serves this machine only; "0.0.0.0" every interface. port 0: any free port. Raises vkmesh.Error when
the port is taken (naming it). stop_serving() or close() stops it.
)doc")
        .def("stop_serving", &PyReconstructor::stopServing,
             "Stops the viewer's server (closing its pages) and returns what it did: pages, messages_sent, bytes_sent, "
             "frames_published, frames_coalesced (an empty dict when not serving).")
        .def("close", &PyReconstructor::close,
             "Releases the GPU memory and the Vulkan device now (rather than when the object is collected). Any later "
             "call raises vkmesh.Error.")
        .def("__enter__", [](py::object self) { return self; })
        .def("__exit__", [](PyReconstructor& self, const py::args&) { self.close(); })
        .def_property_readonly("closed", &PyReconstructor::closed, "Whether close() was called.")
        .def_property_readonly("frames_integrated", &PyReconstructor::framesIntegrated, "How many frames have been fused.")
        .def("__repr__", &PyReconstructor::repr)
        .def_property_readonly("_last_cpp_seconds", &PyReconstructor::lastCppSeconds,
                               "Benchmarks: seconds the last integrate() spent in the C++ Reconstructor::integrate.");

    py::class_<PyDataset>(m, "_Dataset")
        .def(py::init([](const fs::path& path, size_t frames, float maxDepth, const py::object& intrinsics, const py::object& depthScale,
                         bool requirePoses, const std::string& depthTopic, const std::string& colorTopic,
                         const std::string& infoTopic) {
                 DatasetOptions o;
                 o.depthTopic = depthTopic;
                 o.colorTopic = colorTopic;
                 o.infoTopic = infoTopic;
                 o.maxFrames = frames;
                 o.requirePoses = requirePoses;
                 o.maxDepth = maxDepth;
                 if (!intrinsics.is_none()) o.intrinsics = toIntrinsics(intrinsics, 0, 0);
                 if (!depthScale.is_none()) o.depthScale = depthScale.cast<double>();
                 std::unique_ptr<Dataset> ds;
                 {
                     py::gil_scoped_release release;
                     ds = Dataset::open(path, o);
                 }
                 return std::make_unique<PyDataset>(std::move(ds));
             }),
             "path"_a, "frames"_a, "max_depth"_a, "intrinsics"_a, "depth_scale"_a, "require_poses"_a = true,
             "depth_topic"_a = "", "color_topic"_a = "", "info_topic"_a = "")
        .def("__len__", [](const PyDataset& d) { return d.get().size(); })
        .def("load", &PyDataset::load, "index"_a)
        .def_property_readonly("folder", [](const PyDataset& d) { return d.get().folder().string(); })
        .def_property_readonly("kind", [](const PyDataset& d) { return toString(d.get().kind()); })
        .def_property_readonly("intrinsics", [](const PyDataset& d) {
            const Intrinsics& k = d.get().intrinsics();
            return py::make_tuple(k.fx, k.fy, k.cx, k.cy);
        })
        .def_property_readonly("width", [](const PyDataset& d) { return d.get().intrinsics().width; })
        .def_property_readonly("height", [](const PyDataset& d) { return d.get().intrinsics().height; })
        .def_property_readonly("depth_scale", [](const PyDataset& d) { return d.get().depthScale(); })
        .def_property_readonly("has_color", [](const PyDataset& d) { return d.get().hasColor(); })
        .def_property_readonly("warnings", [](const PyDataset& d) { return d.get().warnings(); });

    m.def("_devices", [] {
        std::vector<vk::DeviceInfo> devices;
        {
            py::gil_scoped_release release;
            devices = vk::Context::listDevices();
        }
        py::list out;
        for (const auto& d : devices)
            out.append(py::dict("index"_a = d.index, "name"_a = d.name, "type"_a = d.type, "api_version"_a = d.apiVersion,
                                "driver"_a = d.driver, "suitable"_a = d.suitable, "why_not"_a = d.whyNot,
                                "int64_atomics"_a = d.int64Atomics, "hash_path"_a = d.hashPath));
        return out;
    });

    m.def("_synth", [](const fs::path& out, size_t frames, int width, int height, bool noise, uint32_t seed, const std::string& path,
                       double colorNoise, double exposureDrift, double gtSpacing) {
        synth::SequenceOptions o;
        o.frames = frames;
        o.width = width;
        o.height = height;
        o.intrinsics = synth::kinectIntrinsics(width, height);
        o.noise = noise;
        o.seed = seed;
        o.path = path == "revisit" ? synth::PathKind::Revisit : synth::PathKind::Orbit;
        o.colorNoise = colorNoise;
        o.exposureDrift = exposureDrift;
        o.gtPointSpacing = gtSpacing;
        py::gil_scoped_release release;
        synth::writeTumSequence(out, synth::SyntheticScene::defaultRoom(), o);
    });

    m.def("_read_mesh", [](const fs::path& path) {
        Mesh mesh;
        {
            py::gil_scoped_release release;
            mesh = readMesh(path);   // .glb as glTF, anything else as PLY
        }
        return PyReconstructor::meshToPython(std::move(mesh));
    });

    m.def("_write_mesh", [](const fs::path& path, const py::array& vertices, const py::array& triangles, const py::object& normals,
                            const py::object& colors, const py::object& ages, const py::object& simplify) -> py::object {
        Mesh mesh = meshFromArrays(vertices, triangles, normals, colors, ages);
        meshFormatOf(path);   // an unknown extension fails before any simplification
        std::optional<SimplifyReport> report;
        if (!simplify.is_none()) {
            const double ratio = simplify.cast<double>();
            checkSimplifyRatio(ratio, "simplify=");
            report.emplace();
            py::gil_scoped_release release;
            mesh = simplifyMesh(mesh, ratio, &*report);
        }
        {
            py::gil_scoped_release release;
            writeMesh(path, mesh);
        }
        if (!report) return py::none();
        return py::dict("ratio"_a = report->ratio, "triangles_before"_a = report->trianglesBefore,
                        "triangles_after"_a = report->trianglesAfter, "error_m"_a = report->errorMetres);
    });

    m.attr("_DELTA_ADDED") = uint32_t(DeltaKind::Added);
    m.attr("_DELTA_CHANGED") = uint32_t(DeltaKind::Changed);
    m.attr("_DELTA_REMOVED") = uint32_t(DeltaKind::Removed);

    m.def("_take_validation_messages", [] { return std::exchange(validationMessages(), {}); });

    // The overhead benchmark's C++ side (bench/python_overhead.py): a frame converted once, then the C++ API's
    // integrate on it, timed in C++.
    py::class_<CppFrame>(m, "_CppFrame")
        .def(py::init([](const py::object& depth, const py::object& intrinsics, const py::object& pose, double depthScale,
                         const py::object& color, float maxDepth) {
                 auto f = std::make_unique<CppFrame>();
                 const DepthInput d = checkDepth(depth);
                 convertDepth(d, depthScale, maxDepth, f->depth);
                 f->intrinsics = toIntrinsics(intrinsics, d.width, d.height);
                 f->pose = toPose(pose, "_CppFrame");
                 if (auto c = checkColor(color, d)) convertColor(*c, f->color.emplace());
                 return f;
             }),
             "depth"_a, "intrinsics"_a, "pose"_a, "depth_scale"_a = 5000.0, "color"_a = py::none(), "max_depth"_a = 4.0f);
    m.def("_timed_cpp_integrate", [](PyReconstructor& r, const CppFrame& f) {
        return r.timedCppIntegrate(f.depth, f.color ? &*f.color : nullptr, f.intrinsics, f.pose);
    });
}
