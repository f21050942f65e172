// vkmesh._Dataset, what vkmesh.open_dataset() iterates (vkmesh/__init__.py): the dataset reader (io/dataset.h) with
// its own conversion and checks, each frame's depth, colour and pose as numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <string>
#include <utility>

#include "arrays.h"
#include "bindings.h"
#include "core/types.h"
#include "io/dataset.h"

using namespace pybind11::literals;

namespace vkmesh::python {

namespace {

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

}  // namespace

void bindDataset(py::module_& m) {
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
}

}  // namespace vkmesh::python
