// The parts of vkmesh._vkmesh, each adding its classes and functions to the module: vkmesh_module.cpp calls them
// in this order (after registering Error and CapacityWarning), the order the module has always made them in.
#pragma once

#include <pybind11/pybind11.h>

#include "vk/context.h"

namespace vkmesh::python {

void bindReconstructor(pybind11::module_& m);    // reconstructor.cpp: Reconstructor
void bindDataset(pybind11::module_& m);          // dataset.cpp: _Dataset
void bindModuleFunctions(pybind11::module_& m);  // module_functions.cpp: _devices, _synth, _read_mesh, _write_mesh, ...
void bindBenchmark(pybind11::module_& m);        // reconstructor.cpp: _CppFrame, _timed_cpp_integrate

// reconstructor.cpp: the `device` (None or an index from vkmesh.devices()) and `validation` keywords as the device
// options, checked (ValueError). Reconstructor(), Reconstructor.load() and _merge_maps take them the same way.
vk::ContextOptions deviceOptions(const pybind11::object& device, bool validation);

}  // namespace vkmesh::python
