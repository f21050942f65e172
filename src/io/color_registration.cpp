#include "io/color_registration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace vkmesh {

bool isSameCamera(const ColorCamera& camera, const Intrinsics& depth) {
    const Intrinsics& c = camera.intrinsics;
    return c.fx == depth.fx && c.fy == depth.fy && c.cx == depth.cx && c.cy == depth.cy && c.width == depth.width &&
           c.height == depth.height && camera.depthToColor == Eigen::Matrix4d::Identity();
}

ColorImage registerColorToDepth(const ColorImage& color, const ColorCamera& camera, const DepthImage& depth,
                                const Intrinsics& k, bool occlusionTest) {
    const Intrinsics& ck = camera.intrinsics;
    if (color.width != ck.width || color.height != ck.height || color.rgb.size() != size_t(ck.width) * ck.height * 3)
        throw Error("colour image is " + std::to_string(color.width) + "x" + std::to_string(color.height) +
                    " but its camera's calibration is for " + std::to_string(ck.width) + "x" + std::to_string(ck.height));
    if (depth.width != k.width || depth.height != k.height)
        throw Error("depth image is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                    " but the depth camera's calibration is for " + std::to_string(k.width) + "x" + std::to_string(k.height));
    ColorImage out;
    out.width = k.width;
    out.height = k.height;
    out.rgb.assign(size_t(k.width) * k.height * 3, 0);
    if (isSameCamera(camera, k)) {
        // Exact: the same pixel, no resampling (a projection round trip would move it by rounding).
        out.rgb = color.rgb;
        return out;
    }

    // Every measured depth pixel in the colour camera: position and depth there.
    const Eigen::Matrix3d R = camera.depthToColor.topLeftCorner<3, 3>();
    const Eigen::Vector3d t = camera.depthToColor.topRightCorner<3, 1>();
    const size_t n = size_t(k.width) * k.height;
    std::vector<float> px(n, -1), py(n, -1), pz(n, 0);
    // The nearest point seen through each colour pixel: a coarse z-buffer that finds what the colour camera
    // sees in front of a depth pixel's point (the other side of an edge, seen past it by the baseline).
    std::vector<float> nearest(size_t(ck.width) * ck.height, std::numeric_limits<float>::infinity());
    for (int v = 0; v < k.height; ++v)
        for (int u = 0; u < k.width; ++u) {
            const size_t i = size_t(v) * k.width + u;
            const double z = depth.meters[i];
            if (!(z > 0)) continue;
            const Eigen::Vector3d p(z * (u - k.cx) / k.fx, z * (v - k.cy) / k.fy, z);
            const Eigen::Vector3d q = R * p + t;
            if (!(q.z() > 1e-6)) continue;
            const double x = ck.fx * q.x() / q.z() + ck.cx, y = ck.fy * q.y() / q.z() + ck.cy;
            if (!(x > -0.5 && y > -0.5 && x < ck.width - 0.5 && y < ck.height - 0.5)) continue;
            px[i] = float(x);
            py[i] = float(y);
            pz[i] = float(q.z());
            // Splatted to the pixel and its right/lower neighbours: a depth image coarser than the colour image
            // leaves gaps between its projected points that a nearer surface must not let through.
            const int x0 = int(std::lround(x)), y0 = int(std::lround(y));
            for (int dy = 0; dy <= 1; ++dy)
                for (int dx = 0; dx <= 1; ++dx) {
                    const int xx = std::min(x0 + dx, ck.width - 1), yy = std::min(y0 + dy, ck.height - 1);
                    float& near = nearest[size_t(yy) * ck.width + xx];
                    near = std::min(near, float(q.z()));
                }
        }
    for (size_t i = 0; i < n; ++i) {
        if (!(pz[i] > 0)) continue;  // no depth, or not in the colour camera's view
        const float x = px[i], y = py[i], z = pz[i];
        const int x0 = int(std::lround(x)), y0 = int(std::lround(y));
        // Occluded when something at least 2 cm + 2 % nearer projects to the same colour pixel.
        if (occlusionTest && nearest[size_t(y0) * ck.width + x0] < z - (0.02f + 0.02f * z)) continue;
        // Bilinear, clamped at the border.
        const float fx = std::clamp(x, 0.f, float(ck.width - 1)), fy = std::clamp(y, 0.f, float(ck.height - 1));
        const int xa = int(fx), ya = int(fy);
        const int xb = std::min(xa + 1, ck.width - 1), yb = std::min(ya + 1, ck.height - 1);
        const float ax = fx - xa, ay = fy - ya;
        for (int c = 0; c < 3; ++c) {
            const float top = (1 - ax) * color.at(xa, ya)[c] + ax * color.at(xb, ya)[c];
            const float bottom = (1 - ax) * color.at(xa, yb)[c] + ax * color.at(xb, yb)[c];
            out.rgb[i * 3 + c] = uint8_t(std::clamp(std::lround((1 - ay) * top + ay * bottom), 0L, 255L));
        }
    }
    return out;
}

}  // namespace vkmesh
