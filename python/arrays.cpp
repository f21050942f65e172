// The shared half of vkmesh._vkmesh's bindings (arrays.h): numpy arrays checked and converted with the dataset
// reader's own conversion and checks, meshes to and from vkmesh.Mesh, validation messages and capacity warnings.
#include "arrays.h"

#include <pybind11/pybind11.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "io/dataset.h"
#include "io/parsers.h"

using namespace pybind11::literals;

namespace vkmesh::python {

// ---------------------------------------------------------------------------------------------------
// numpy helpers

std::string shapeOf(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeOf(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

double shortest(float v) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof(text), v).ptr;
    double out = v;
    std::from_chars(text, end, out);
    return out;
}

py::array asArray(const py::handle& x) {
    if (py::isinstance<py::array>(x)) return py::reinterpret_borrow<py::array>(x);
    return py::module_::import("numpy").attr("asarray")(x);
}

py::array contiguous(py::array a) {
    if (a.flags() & py::array::c_style) return a;
    return py::module_::import("numpy").attr("ascontiguousarray")(a);
}

// ---------------------------------------------------------------------------------------------------
// Frame inputs: depth, colour, intrinsics, pose

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
// Meshes

py::object meshToPython(Mesh&& m) {
    py::object normals = m.normals.empty() ? py::object(py::none()) : py::object(moveToArray<float>(std::move(m.normals), 3));
    py::object colors = m.colors.empty() ? py::object(py::none()) : py::object(moveToArray<uint8_t>(std::move(m.colors), 3));
    py::object ages = m.vertexAge.empty() ? py::object(py::none()) : py::object(moveToArray<uint32_t>(std::move(m.vertexAge), 1));
    return py::module_::import("vkmesh").attr("Mesh")(moveToArray<float>(std::move(m.positions), 3),
                                                      moveToArray<uint32_t>(std::move(m.triangles), 3), "normals"_a = normals,
                                                      "colors"_a = colors, "ages"_a = ages);
}

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

// ---------------------------------------------------------------------------------------------------
// Validation messages and capacity warnings

std::vector<std::string>& validationMessages() {
    static std::vector<std::string> messages;
    return messages;
}

void publishMessages(std::vector<std::string>&& messages) {
    auto& all = validationMessages();
    for (auto& m : messages) all.push_back(std::move(m));
}

void warnCapacity(const std::vector<std::string>& warnings, uint32_t frame) {
    if (warnings.empty()) return;
    py::object category = py::module_::import("vkmesh._vkmesh").attr("CapacityWarning");
    for (const auto& w : warnings) {
        const std::string text = "frame " + std::to_string(frame) + ": " + w;
        if (PyErr_WarnEx(category.ptr(), text.c_str(), 1) < 0) throw py::error_already_set();
    }
}

}  // namespace vkmesh::python
