// vkmesh._vkmesh's free functions: the settings' descriptions, Vulkan devices, the synthetic sequence writer, mesh files (PLY, glTF) read and
// written, saved maps merged (api/map_merge.h), the mesh delta kinds and the validation messages collected from every Reconstructor.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/map_merge.h"
#include "api/run_stats_json.h"
#include "api/settings.h"
#include "core/frame_store.h"
#include "core/map_format.h"
#include "arrays.h"
#include "bindings.h"
#include "core/mesh.h"
#include "core/mesh_delta.h"
#include "io/mesh_file.h"
#include "io/mesh_simplify.h"
#include "io/ply.h"
#include "slam/session_join.h"
#include "slam/pose_graph.h"
#include "slam/session_join_json.h"
#include "slam/session_registration.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "gpu/map_corrector.h"
#include "vk/context.h"

using namespace pybind11::literals;

namespace vkmesh::python {

void bindModuleFunctions(py::module_& m) {
    // Every setting as api/settings.h describes it (tests/python/test_settings.py checks the keywords against it).
    m.def("_settings", [] {
        py::list out;
        for (const SettingDescription& d : settingDescriptions())
            out.append(py::dict("cli"_a = d.cli, "python"_a = d.python, "kind"_a = toString(d.kind), "default"_a = d.defaultValue,
                                "min"_a = d.min, "max"_a = d.max, "min_exclusive"_a = d.minExclusive, "choices"_a = d.choices,
                                "help"_a = d.help, "cli_negates"_a = d.cliNegates, "deprecated"_a = d.deprecated,
                                "from_map"_a = d.fromMap != nullptr));
        return out;
    });
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
        return meshToPython(std::move(mesh));
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

    // A mesh path's format checked (vkmesh.Error for an extension vkmesh cannot write), before work whose mesh it is.
    m.def("_check_mesh_path", [](const fs::path& path) { meshFormatOf(path); });

    // vkmesh.merge_maps(): mergeMaps (api/map_merge.h), or with registerSessions slam::joinSessions, without the GIL; returns (the statistics of `vkmesh merge --stats`
    // as a dict, parsed from mergeReportJson's text by Python's json module, and the merged mesh as a vkmesh.Mesh or None).
    m.def("_merge_maps", [](const std::vector<fs::path>& inputs, const fs::path& output, bool keepFrames, double framesBudgetMb,
                            const std::string& framesSpill, const py::object& device, bool validation, bool returnMesh,
                            double tileSize, const fs::path& tilesDir, bool registerSessions) {
        if (inputs.empty()) throw py::value_error("merge_maps: no maps given (inputs is empty)");
        if (registerSessions && inputs.size() < 2) throw py::value_error("merge_maps: register=True joins two maps or more (the later ones registered to the first)");
        if (registerSessions && output.empty()) throw py::value_error("merge_maps: register=True needs an output map");
        if (!(framesBudgetMb > 0) || !(framesBudgetMb < 1e12))
            throw py::value_error("frames_budget_mb " + std::to_string(framesBudgetMb) + " must be positive");
        MergeOptions options;
        options.device = deviceOptions(device, validation);
        options.keepFrames = keepFrames;
        options.frames.memoryBudgetBytes = size_t(framesBudgetMb * 1024 * 1024);
        options.frames.spillFolder = framesSpill;
        options.returnMesh = returnMesh;
        if (!tilesDir.empty()) {
            if (!(tileSize > 0) || !(tileSize < 1e9)) throw py::value_error("tile_size " + std::to_string(tileSize) + " must be a positive number of metres");
            fs::create_directories(tilesDir);
            options.tileSize = tileSize;
            options.tileSink = [tilesDir](const TileKey& t, const Mesh& mesh) { writeMesh(tilesDir / tileFileName(t), mesh); };
        }
        MergeReport report;
        std::string stats;
        {
            py::gil_scoped_release release;
            if (registerSessions) {   // sessions of one place, each in its own frame (slam/session_join.h)
                slam::JoinOptions join;
                join.merge = options;
                slam::JoinReport joined = slam::joinSessions(inputs, output, join);
                report = std::move(joined.merge);
                nlohmann::json json = mergeReportJson(report);
                json["registration"] = slam::joinReportJson(joined, inputs);
                stats = json.dump();
            } else {
                report = mergeMaps(inputs, output, options);
                stats = mergeReportJson(report).dump();
            }
        }
        py::object mesh = returnMesh ? meshToPython(std::move(report.mesh)) : py::none();
        return py::make_tuple(py::module_::import("json").attr("loads")(stats), mesh);
    });

    // ---- tiles made on their own (vkmesh.list_tiles, vkmesh.merge_tiles; api/map_merge.h planTiles, mergeTiles) ----
    // list_tiles: the tiles of the sum from the inputs' block tables alone, as a list of (x, y, z) and the sum's blocks.
    m.def("_list_tiles", [](const std::vector<fs::path>& inputs, double tileSize) {
        if (inputs.empty()) throw py::value_error("list_tiles: no maps given (inputs is empty)");
        if (!(tileSize > 0) || !(tileSize < 1e9)) throw py::value_error("tile_size " + std::to_string(tileSize) + " must be a positive number of metres");
        TilePlan plan;
        {
            py::gil_scoped_release release;
            plan = planTiles(inputs, tileSize);
        }
        py::list tiles;
        for (const TileKey& t : plan.tiles) tiles.append(py::make_tuple(t[0], t[1], t[2]));
        return py::dict("tiles"_a = tiles, "blocks"_a = plan.blocks, "frames_integrated"_a = plan.framesIntegrated);
    });
    // merge_tiles: the tiles asked for (None: every tile), each from its own blocks of the inputs, written to
    // tilesDir/tile_X_Y_Z.ply under a temporary name (.writing.tile_X_Y_Z.ply) and renamed, so that a tile file is
    // whole or absent (a worker killed half way leaves none under the name).
    m.def("_merge_tiles", [](const std::vector<fs::path>& inputs, const fs::path& tilesDir, double tileSize,
                             const std::optional<std::vector<std::array<int32_t, 3>>>& tiles, const py::object& device, bool validation) {
        if (inputs.empty()) throw py::value_error("merge_tiles: no maps given (inputs is empty)");
        if (!(tileSize > 0) || !(tileSize < 1e9)) throw py::value_error("tile_size " + std::to_string(tileSize) + " must be a positive number of metres");
        TileOptions options;
        options.device = deviceOptions(device, validation);
        options.tileSize = tileSize;
        std::map<TileKey, std::string> written;
        options.tileSink = [&](const TileKey& t, const Mesh& mesh) {
            const fs::path path = tilesDir / tileFileName(t), partial = tilesDir / (".writing." + tileFileName(t));
            writeMesh(partial, mesh);
            fs::rename(partial, path);
            written[t] = path.string();
        };
        TilesReport report;
        {
            py::gil_scoped_release release;
            const std::vector<TileKey> keys = tiles ? *tiles : planTiles(inputs, tileSize).tiles;
            fs::create_directories(tilesDir);
            report = mergeTiles(inputs, keys, options);
        }
        py::list perTile;
        size_t triangles = 0;
        for (const TileReport& r : report.tiles) {
            auto it = written.find(r.tile);
            if (it == written.end()) {   // no triangle: a file left by an earlier run under its name is not this tile
                std::error_code ignored;
                fs::remove(tilesDir / tileFileName(r.tile), ignored);
            }
            perTile.append(py::dict("tile"_a = py::make_tuple(r.tile[0], r.tile[1], r.tile[2]),
                                    "path"_a = it != written.end() ? py::object(py::str(it->second)) : py::object(py::none()),
                                    "blocks_read"_a = r.blocksRead, "blocks_meshed"_a = r.blocksMeshed, "vertices"_a = r.vertices,
                                    "triangles"_a = r.triangles, "ms"_a = py::dict("read"_a = r.readMs, "mesh"_a = r.meshMs)));
            triangles += r.triangles;
        }
        return py::dict("tiles"_a = perTile, "count"_a = written.size(), "triangles"_a = triangles,
                        "max_blocks_host"_a = report.hostBlocksMax, "max_blocks_gpu"_a = report.gpuBlocksMax,
                        "table_blocks"_a = report.tableBlocks, "ms"_a = py::dict("open"_a = report.openMs));
    });

    // ---- maps registered, pose graphs solved (vkmesh.register_maps, vkmesh.optimise_pose_graph; vkmesh.batch --loop-closure) ----
    // register_maps: slam::registerSessions over two saved maps' kept frames (their .vkframes beside them), without the GIL.
    m.def("_register_maps", [](const fs::path& firstPath, const fs::path& secondPath) {
        slam::SessionRegistration r;
        {
            py::gil_scoped_release release;
            auto loadStore = [](const fs::path& mapPath) {
                const fs::path store = gpu::frameStorePathOf(mapPath);
                if (!fs::exists(store))
                    throw Error(mapPath.string() + " has no frame store beside it (" + store.string() +
                                "): registering maps needs their kept frames (fuse with keep_frames=True)");
                return FrameStore::load(store.string(), map::readFile(mapPath).saveId);
            };
            const FrameStore first = loadStore(firstPath), second = loadStore(secondPath);
            r = slam::registerSessions(first, second);
        }
        py::list transform;
        for (int row = 0; row < 4; ++row) {
            py::list line;
            for (int col = 0; col < 4; ++col) line.append(r.secondToFirst(row, col));
            transform.append(line);
        }
        return py::dict("transform"_a = transform, "pairs_registered"_a = r.registrations, "pairs_verified"_a = r.verified,
                        "pairs_agreeing"_a = r.agreeing, "spread_m"_a = r.spreadMetres, "spread_degrees"_a = r.spreadDegrees,
                        "keyframes"_a = py::make_tuple(r.firstKeyframes, r.secondKeyframes), "ms"_a = r.milliseconds);
    });

    // optimise_pose_graph: a thin wrapper of slam::PoseGraph (diagonal information from each edge's sigmas).
    m.def("_optimise_pose_graph", [](const std::vector<std::array<double, 16>>& poses, const py::list& edges, double huber, int maxIterations) {
        auto toPose = [](const std::array<double, 16>& rowMajor) {
            Pose p = Pose::Identity();
            for (int row = 0; row < 4; ++row)
                for (int col = 0; col < 4; ++col) p(row, col) = rowMajor[size_t(row * 4 + col)];
            return p;
        };
        slam::PoseGraph graph;
        for (const auto& p : poses) graph.addNode(toPose(p));
        for (size_t i = 0; i < edges.size(); ++i) {
            const py::dict e = edges[i].cast<py::dict>();
            slam::PoseGraphEdge edge;
            edge.from = e["from"].cast<int>();
            edge.to = e["to"].cast<int>();
            edge.measured = toPose(e["measured"].cast<std::array<double, 16>>());
            const double sigmaM = e["sigma_m"].cast<double>(), sigmaDeg = e["sigma_deg"].cast<double>();
            if (!(sigmaM > 0) || !(sigmaDeg > 0))
                throw py::value_error("edge " + std::to_string(i) + ": sigma_m and sigma_deg must be positive");
            edge.information = slam::diagonalInformation(sigmaM, sigmaDeg * 3.14159265358979323846 / 180.0);
            edge.loop = e.contains("loop") ? e["loop"].cast<bool>() : false;
            graph.addEdge(edge);   // Error for an unknown node
        }
        slam::PoseGraphSolve solve;
        std::vector<double> errors;
        {
            py::gil_scoped_release release;
            solve = graph.optimise(maxIterations, huber);
            for (size_t i = 0; i < graph.edges().size(); ++i) errors.push_back(graph.whitenedError(i));
        }
        py::list out;
        for (const Pose& p : graph.poses()) {
            py::list rows;
            for (int row = 0; row < 4; ++row) {
                py::list line;
                for (int col = 0; col < 4; ++col) line.append(p(row, col));
                rows.append(line);
            }
            out.append(rows);
        }
        return py::dict("poses"_a = out, "converged"_a = solve.converged, "iterations"_a = solve.iterations,
                        "initial_cost"_a = solve.initialCost, "final_cost"_a = solve.finalCost, "edge_errors"_a = errors,
                        "ms"_a = solve.milliseconds);
    });

    m.attr("_DELTA_ADDED") = uint32_t(DeltaKind::Added);
    m.attr("_DELTA_CHANGED") = uint32_t(DeltaKind::Changed);
    m.attr("_DELTA_REMOVED") = uint32_t(DeltaKind::Removed);

    m.def("_take_validation_messages", [] { return std::exchange(validationMessages(), {}); });
}

}  // namespace vkmesh::python
