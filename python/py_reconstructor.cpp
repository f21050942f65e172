// PyReconstructor's members (py_reconstructor.h): each call checks and converts its arguments with the GIL held, then
// runs the vkmesh::Reconstructor under the object's mutex without the GIL, and returns numpy arrays and dicts.
#include "py_reconstructor.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/exported_mesh.h"
#include "api/run_stats_json.h"
#include "core/mesh_delta.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"

using namespace pybind11::literals;

namespace vkmesh::python {

namespace {

const char* colorModeName(ColorFusion mode) {
    switch (mode) {
        case ColorFusion::Off: return "off";
        case ColorFusion::Average: return "average";
        case ColorFusion::Recent: return "recent";
    }
    return "?";
}

}  // namespace

py::object PyReconstructor::integrate(const py::object& depthObject, const py::object& intrinsicsObject,
                                      const py::object& poseObject, double depthScale, const py::object& colorObject) {
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

void PyReconstructor::correct(const py::object& framesObject, const py::object& posesObject) {
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

size_t PyReconstructor::pendingCorrections() {
    return locked([](Reconstructor& rec) { return rec.pendingCorrections(); });
}

py::dict PyReconstructor::finishCorrections() {
    gpu::CorrectionReport r = locked([](Reconstructor& rec) { return rec.finishCorrections(); });
    return correctionDict(r);
}

py::dict PyReconstructor::lastCorrections() {
    gpu::CorrectionReport r = locked([](Reconstructor& rec) { return rec.lastCorrections(); });
    return correctionDict(r);
}

py::dict PyReconstructor::correctionDict(const gpu::CorrectionReport& r) {
    return py::dict("frames_refused"_a = r.framesRefused, "frames"_a = r.frames, "blocks_freed"_a = r.blocksFreed,
                    "observations_dropped"_a = r.observationsDropped, "ms"_a = r.milliseconds, "warnings"_a = r.warnings);
}

py::array PyReconstructor::trajectory() {
    std::vector<Pose> poses = locked([](Reconstructor& rec) { return rec.trajectory(); });
    py::array_t<double> out({py::ssize_t(poses.size()), py::ssize_t(4), py::ssize_t(4)});
    auto view = out.mutable_unchecked<3>();
    for (size_t i = 0; i < poses.size(); ++i)
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) view(py::ssize_t(i), r, c) = poses[i](r, c);
    return out;
}

py::object PyReconstructor::mesh() {
    Mesh m = locked([](Reconstructor& rec) {
        const gpu::ExportedMesh exported = rec.downloadMesh();
        // Ages in the GPU's frame numbers, as `vkmesh fuse` writes them.
        return toMesh(exported, rec.volume() ? rec.volume()->frameNumber() : 0u);
    });
    return meshToPython(std::move(m));
}

py::object PyReconstructor::deltas() {
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

py::dict PyReconstructor::stats() {
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
    d["resident_blocks"] = c.residentBlocks;
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

py::dict PyReconstructor::withRunStats(py::dict own, const std::string& runJson) {
    const py::dict run = py::module_::import("json").attr("loads")(runJson);
    addMissing(own, run);
    return own;
}

void PyReconstructor::addMissing(py::dict& into, const py::dict& from) {
    for (const auto& [key, value] : from) {
        if (!into.contains(key)) {
            into[key] = value;
        } else if (py::isinstance<py::dict>(into[key]) && py::isinstance<py::dict>(value)) {
            py::dict inner = into[key];
            addMissing(inner, value.cast<py::dict>());
        }
    }
}

void PyReconstructor::save(const fs::path& path) {
    locked([&](Reconstructor& rec) { rec.save(path); });
}

void PyReconstructor::close() {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
#ifdef VKMESH_HAVE_VIEWER
    server_.reset();
#endif
    rec_.reset();
}

std::string PyReconstructor::serve(int port, const std::string& host) {
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

py::dict PyReconstructor::stopServing() {
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

bool PyReconstructor::closed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return !rec_;
}

uint32_t PyReconstructor::framesIntegrated() {
    return locked([](Reconstructor& rec) { return rec.framesIntegrated(); });
}

std::string PyReconstructor::repr() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!rec_) return "<vkmesh.Reconstructor (closed)>";
    const gpu::GpuVolume* v = rec_->volume();
    const VolumeParams& p = v ? v->config().params : options_.volume.params;
    char voxel[32];
    std::snprintf(voxel, sizeof(voxel), "%g", p.voxelSize);
    return "<vkmesh.Reconstructor voxel " + std::string(voxel) + " m, " + std::to_string(rec_->framesIntegrated()) +
           " frames, on " + rec_->context().info().name + ">";
}

double PyReconstructor::lastCppSeconds() {
    std::lock_guard<std::mutex> lock(mutex_);
    return lastCppSeconds_;
}

double PyReconstructor::timedCppIntegrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                          const Pose& pose) {
    return locked([&](Reconstructor& rec) {
        const auto t0 = std::chrono::steady_clock::now();
        rec.integrate(depth, color, intrinsics, pose);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    });
}

float PyReconstructor::maxDepth(Reconstructor& rec) const {
    return rec.volume() ? rec.volume()->config().params.maxDepth : options_.volume.params.maxDepth;
}

}  // namespace vkmesh::python
