// vkmesh._vkmesh's module definition: PYBIND11_MODULE registers vkmesh.Error and vkmesh.CapacityWarning, then calls
// each file's bind function (bindings.h) in the order the module has always made its attributes in.
//
// vkmesh._vkmesh is the compiled half of the Python package `vkmesh` (docs/PYTHON.md; the pure-Python half,
// vkmesh/__init__.py, holds the data classes and the dataset iteration). Bindings over the C++ API with no
// reconstruction code of their own: vkmesh::Reconstructor (api/reconstructor.h) fuses and meshes, the dataset
// reader (io/dataset.h) reads sequences, io/ply.h reads and writes meshes, synth/ writes synthetic sequences.
// What the module adds: numpy arrays checked and converted, with the dataset reader's own conversion (uint16 depth
// to metres) and checks (intrinsics, rigid poses), so that the same frames give the CLI's floats and messages.
// The files: arrays.h (the conversions and messages every binding shares), py_reconstructor.h (PyReconstructor,
// what vkmesh.Reconstructor wraps), reconstructor.cpp (its settings and binding, and the overhead benchmark's),
// dataset.cpp (vkmesh._Dataset), module_functions.cpp (devices, synth, mesh files, validation messages).
//
// Errors: a bad argument (dtype, shape, value, a non-rigid pose) raises ValueError with vkmesh's message;
// whatever vkmesh::Error reports (Vulkan, capacities that do not fit the device, files) raises vkmesh.Error,
// a RuntimeError. The GIL is released while images are converted and while the GPU works; each Reconstructor
// has a mutex so that its C++ object is used by one thread at a time, as api/reconstructor.h requires.
#include <pybind11/pybind11.h>

#include "arrays.h"
#include "bindings.h"
#include "core/types.h"

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

    bindReconstructor(m);
    bindDataset(m);
    bindModuleFunctions(m);
    bindBenchmark(m);
}
