// The visibility mask: which GT points a dataset's depth frames saw (seenMask), frames tested in parallel
// batches against spatial chunks of the points.
#include "eval/evaluate.h"
#include "eval/evaluate_internal.h"

#include "io/dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace vkmesh::eval {

using detail::number;
using detail::parallelChunks;
using detail::threadCount;

std::vector<bool> seenMask(const std::vector<Eigen::Vector3f>& gt, const Dataset& dataset, size_t frameStride,
                           double tolerance, std::vector<std::string>* warnings) {
    if (!(std::isfinite(tolerance) && tolerance >= 0))
        throw Error("seen tolerance " + number(tolerance) + " must be finite and >= 0");
    const size_t stride = std::max<size_t>(frameStride, 1);
    const float tol = float(std::max(tolerance, 3.0 / dataset.depthScale()));
    const Intrinsics& k = dataset.intrinsics();
    std::vector<uint8_t> seen(gt.size(), 0);
    if (gt.empty() || dataset.size() == 0) return std::vector<bool>(gt.size(), false);

    // The points in spatial chunks (cubes of a coarse grid), so that a frame can skip a whole chunk that is
    // outside its view. Each chunk keeps the indices of its points not seen yet, in [begin, begin + live).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& p : gt)
        if (p.allFinite()) lo = lo.cwiseMin(p.cast<double>()), hi = hi.cwiseMax(p.cast<double>());
    if (!(lo.array() <= hi.array()).all()) return std::vector<bool>(gt.size(), false);  // no finite point
    double side = 0.25;
    int n[3];
    for (;;) {
        double cells = 1;
        for (int a = 0; a < 3; ++a) cells *= (n[a] = int(std::floor((hi[a] - lo[a]) / side)) + 1);
        if (cells <= 1e6) break;
        side *= 1.5;
    }
    std::vector<uint32_t> cellStart(size_t(n[0]) * n[1] * n[2] + 1, 0), cellOf(gt.size(), UINT32_MAX);
    for (size_t i = 0; i < gt.size(); ++i) {
        if (!gt[i].allFinite()) continue;
        size_t c = 0;
        for (int a = 2; a >= 0; --a)
            c = c * n[a] + size_t(std::clamp(int(std::floor((gt[i][a] - lo[a]) / side)), 0, n[a] - 1));
        cellOf[i] = uint32_t(c);
        ++cellStart[c + 1];
    }
    for (size_t c = 0; c + 1 < cellStart.size(); ++c) cellStart[c + 1] += cellStart[c];
    std::vector<uint32_t> order(cellStart.back());
    {
        std::vector<uint32_t> fill(cellStart.begin(), cellStart.end() - 1);
        for (size_t i = 0; i < gt.size(); ++i)
            if (cellOf[i] != UINT32_MAX) order[fill[cellOf[i]]++] = uint32_t(i);
    }
    struct Chunk {
        Eigen::Vector3f centre;
        uint32_t begin, live;
    };
    std::vector<Chunk> chunks;
    for (size_t c = 0; c + 1 < cellStart.size(); ++c) {
        if (cellStart[c + 1] == cellStart[c]) continue;
        const size_t x = c % n[0], y = (c / n[0]) % n[1], z = c / (size_t(n[0]) * n[1]);
        chunks.push_back({(lo + side * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5)).cast<float>(), cellStart[c],
                          cellStart[c + 1] - cellStart[c]});
    }
    const float radius = float(side * std::sqrt(3.0) / 2 * 1.001);

    std::vector<size_t> frames;
    for (size_t i = 0; i < dataset.size(); i += stride) frames.push_back(i);

    struct Camera {
        float r[3][4];         // world -> camera rows
        float planes[4][3];    // unit normals of the frustum's side planes (camera frame, through the origin)
        float farthest = 0;    // largest valid depth + tolerance
        DepthImage depth;
        bool ok = false;
        std::string error;
    };
    // A point projecting to (u, v) is looked up when -1 <= u < w and -1 <= v < h (its 4 surrounding pixels):
    // in the camera frame fx x + (cx + 1) z >= 0, -fx x + (w - cx) z > 0, and the same for y.
    auto setPlanes = [&](Camera& cam) {
        const float w = float(cam.depth.width), h = float(cam.depth.height);
        const float raw[4][3] = {{k.fx, 0, k.cx + 1}, {-k.fx, 0, w - k.cx}, {0, k.fy, k.cy + 1}, {0, -k.fy, h - k.cy}};
        for (int p = 0; p < 4; ++p) {
            const float len = std::sqrt(raw[p][0] * raw[p][0] + raw[p][1] * raw[p][1] + raw[p][2] * raw[p][2]);
            for (int a = 0; a < 3; ++a) cam.planes[p][a] = raw[p][a] / len;
        }
        float farthest = 0;
        for (float d : cam.depth.meters) farthest = std::max(farthest, d);
        cam.farthest = farthest + tol;
    };

    // Frames are loaded in batches, in parallel; then every chunk is checked against the whole batch.
    const size_t batchSize = 4 * threadCount();
    std::vector<Camera> batch(batchSize);
    for (size_t first = 0; first < frames.size(); first += batchSize) {
        const size_t count = std::min(batchSize, frames.size() - first);
        parallelChunks(count, 1, [&](size_t b, size_t e) {
            for (size_t j = b; j < e; ++j) {
                Camera& cam = batch[j];
                const size_t f = frames[first + j];
                const Pose& c2w = dataset.frame(f).cameraToWorld;
                const Eigen::Matrix3d rt = c2w.topLeftCorner<3, 3>().transpose();
                const Eigen::Vector3d t = -rt * c2w.topRightCorner<3, 1>();
                for (int r = 0; r < 3; ++r) {
                    for (int c = 0; c < 3; ++c) cam.r[r][c] = float(rt(r, c));
                    cam.r[r][3] = float(t[r]);
                }
                try {
                    cam.depth = dataset.loadDepth(f);
                    cam.ok = true;
                    setPlanes(cam);
                } catch (const Error& err) {
                    cam.ok = false;
                    cam.error = "frame " + std::to_string(f) + " skipped: " + err.what();
                }
            }
        });
        for (size_t j = 0; j < count; ++j)
            if (!batch[j].ok && warnings) warnings->push_back(batch[j].error);

        parallelChunks(chunks.size(), 16, [&](size_t cb, size_t ce) {
            for (size_t ci = cb; ci < ce; ++ci) {
                Chunk& chunk = chunks[ci];
                for (size_t j = 0; j < count && chunk.live > 0; ++j) {
                    const Camera& cam = batch[j];
                    if (!cam.ok) continue;
                    float cc[3];
                    for (int r = 0; r < 3; ++r)
                        cc[r] = cam.r[r][0] * chunk.centre.x() + cam.r[r][1] * chunk.centre.y() +
                                cam.r[r][2] * chunk.centre.z() + cam.r[r][3];
                    if (cc[2] + radius <= 0 || cc[2] - radius >= cam.farthest) continue;
                    bool outside = false;
                    for (int p = 0; p < 4 && !outside; ++p)
                        outside = cam.planes[p][0] * cc[0] + cam.planes[p][1] * cc[1] + cam.planes[p][2] * cc[2] < -radius;
                    if (outside) continue;

                    const int w = cam.depth.width, h = cam.depth.height;
                    const float* depth = cam.depth.meters.data();
                    uint32_t* list = order.data() + chunk.begin;
                    uint32_t kept = 0;
                    for (uint32_t l = 0; l < chunk.live; ++l) {
                        const uint32_t i = list[l];
                        const Eigen::Vector3f& p = gt[i];
                        float q[3];
                        for (int r = 0; r < 3; ++r)
                            q[r] = cam.r[r][0] * p.x() + cam.r[r][1] * p.y() + cam.r[r][2] * p.z() + cam.r[r][3];
                        bool hit = false;
                        if (q[2] > 1e-6f) {
                            const float u = k.fx * q[0] / q[2] + k.cx, v = k.fy * q[1] / q[2] + k.cy;
                            // The (up to) 4 pixels whose centres surround the projection.
                            const float fu = std::floor(u), fv = std::floor(v);
                            if (fu >= -1 && fv >= -1 && fu < float(w) && fv < float(h)) {
                                const int u0 = int(fu), v0 = int(fv);
                                for (int dv = 0; dv < 2 && !hit; ++dv)
                                    for (int du = 0; du < 2 && !hit; ++du) {
                                        const int x = u0 + du, y = v0 + dv;
                                        if (x < 0 || y < 0 || x >= w || y >= h) continue;
                                        const float d = depth[size_t(y) * w + x];
                                        hit = d > 0 && std::abs(q[2] - d) < tol;
                                    }
                            }
                        }
                        if (hit)
                            seen[i] = 1;
                        else
                            list[kept++] = i;
                    }
                    chunk.live = kept;
                }
            }
        });
    }
    return std::vector<bool>(seen.begin(), seen.end());
}

}  // namespace vkmesh::eval
