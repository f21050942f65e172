// What the bindings of vkmesh._vkmesh share (arrays.cpp): numpy arrays checked and converted to and from vkmesh's
// types (depth, colour, intrinsics, poses, meshes), and the validation messages and capacity warnings they publish.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>              // in every file of the module: the same casters everywhere
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.h"
#include "core/types.h"

namespace py = pybind11;

namespace vkmesh::python {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------
// numpy helpers

// The shape as Python prints it, "(480, 640)", for messages.
std::string shapeOf(const py::array& a);

std::string dtypeOf(const py::array& a);

// A float setting as Python shows it: the shortest decimal that reads back as the same float (0.03, where the
// CLI's --stats JSON prints the float's exact value, 0.029999999329447746). Converting it back gives `v` exactly.
double shortest(float v);

// Any array-like as a numpy array (lists become arrays, whose dtype the caller then checks).
py::array asArray(const py::handle& x);

// A C-contiguous array: arrays that are not (a slice, a transposed view) are copied once.
py::array contiguous(py::array a);

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

DepthInput checkDepth(const py::handle& object);

// Metres for the GPU, into `out` (its buffer reused from frame to frame). uint16: the dataset reader's own
// conversion (io::rawDepthToMeters), so the same PNG gives the same floats as `vkmesh fuse`. float32: NaN and 0
// mean no measurement; beyond maxDepth becomes 0, as the reader does. Runs without the GIL.
void convertDepth(const DepthInput& d, double depthScale, float maxDepth, DepthImage& out);

// A colour image registered to the depth image: uint8 H x W x 3 (red, green, blue), C-contiguous.
std::optional<py::array> checkColor(const py::handle& object, const DepthInput& depth);

void convertColor(const py::array& c, ColorImage& out);

// (fx, fy, cx, cy) or a 3 x 3 camera matrix, checked as the dataset reader checks --intrinsics.
Intrinsics toIntrinsics(const py::handle& object, int width, int height);

// A 4 x 4 camera-to-world matrix, checked as the dataset reader checks every pose it reads (validatePose).
py::array poseToPython(const Pose& pose);

Pose toPose(const py::handle& object, const std::string& where);

py::array_t<double> poseToArray(const Pose& pose);

// ---------------------------------------------------------------------------------------------------
// Meshes

// A Mesh as a vkmesh.Mesh, its arrays handed to numpy without a copy.
py::object meshToPython(Mesh&& m);

// vkmesh.Mesh's arrays as a Mesh, for writing (dtypes and shapes checked).
Mesh meshFromArrays(const py::array& vertices, const py::array& triangles, const py::object& normals, const py::object& colors,
                    const py::object& ages);

// ---------------------------------------------------------------------------------------------------
// Validation messages and capacity warnings

// Validation-layer messages of every Reconstructor, collected after each call (with the GIL held) until
// vkmesh.validation_messages() takes them: the test suite fails on any, as the C++ tests do.
std::vector<std::string>& validationMessages();

void publishMessages(std::vector<std::string>&& messages);

// A frame's capacity problems (FrameReport::warnings: something did not fit and was skipped; what was fused
// before is kept) as vkmesh.CapacityWarning, which a program can turn into an exception with warnings.simplefilter.
void warnCapacity(const std::vector<std::string>& warnings, uint32_t frame);

}  // namespace vkmesh::python
