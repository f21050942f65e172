// vkmesh._vkmesh's free functions: the settings' descriptions, Vulkan devices, the synthetic sequence writer, mesh files (PLY, glTF) read and
// written, saved maps merged (api/map_merge.h), the mesh delta kinds and the validation messages collected from every Reconstructor.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/map_merge.h"
#include "api/run_stats_json.h"
#include "api/settings.h"
#include "arrays.h"
#include "bindings.h"
#include "core/mesh.h"
#include "core/mesh_delta.h"
#include "io/mesh_file.h"
#include "io/mesh_simplify.h"
#include "io/ply.h"
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
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

    // vkmesh.merge_maps(): mergeMaps (api/map_merge.h) without the GIL; returns (the statistics of `vkmesh merge --stats`
    // as a dict, parsed from mergeReportJson's text by Python's json module, and the merged mesh as a vkmesh.Mesh or None).
    m.def("_merge_maps", [](const std::vector<fs::path>& inputs, const fs::path& output, bool keepFrames, double framesBudgetMb,
                            const std::string& framesSpill, const py::object& device, bool validation, bool returnMesh,
                            double tileSize, const fs::path& tilesDir) {
        if (inputs.empty()) throw py::value_error("merge_maps: no maps given (inputs is empty)");
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
            report = mergeMaps(inputs, output, options);
            stats = mergeReportJson(report).dump();
        }
        py::object mesh = returnMesh ? meshToPython(std::move(report.mesh)) : py::none();
        return py::make_tuple(py::module_::import("json").attr("loads")(stats), mesh);
    });

    m.attr("_DELTA_ADDED") = uint32_t(DeltaKind::Added);
    m.attr("_DELTA_CHANGED") = uint32_t(DeltaKind::Changed);
    m.attr("_DELTA_REMOVED") = uint32_t(DeltaKind::Removed);

    m.def("_take_validation_messages", [] { return std::exchange(validationMessages(), {}); });
}

}  // namespace vkmesh::python
