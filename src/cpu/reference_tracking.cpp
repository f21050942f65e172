#include "cpu/reference_tracking.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/camera.h"

namespace vkmesh::cpu {
namespace {

bool measured(float d, const gpu::TrackParamsGpu& p) {
    return d >= p.minDepth && d > 0.0f && (p.maxDepth <= 0.0f || d <= p.maxDepth) && !std::isinf(d);
}

Eigen::Vector3f backProject(int x, int y, float d, const Intrinsics& k) {
    return {(float(x) - k.cx) / k.fx * d, (float(y) - k.cy) / k.fy * d, d};
}

Eigen::Vector3f rotate(const RigidRows& m, const Eigen::Vector3f& v) {
    Eigen::Vector3f q;
    for (int i = 0; i < 3; ++i) q[i] = m.r[i][0] * v.x() + m.r[i][1] * v.y() + m.r[i][2] * v.z();
    return q;
}

std::vector<float> filterDepth(const DepthImage& raw, const gpu::TrackParamsGpu& p) {
    const int w = raw.width, h = raw.height;
    std::vector<float> out(size_t(w) * h, 0.0f);
    const int radius = std::min(int(p.filterRadius), 4);
    const float spatial = -0.5f / (p.filterSpatialSigma * p.filterSpatialSigma);
    const float range = -0.5f / (p.filterDepthSigma * p.filterDepthSigma);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float centre = raw.meters[size_t(y) * w + x];
            if (!measured(centre, p)) continue;
            float sum = 0.0f, weights = 0.0f;
            for (int dy = -radius; dy <= radius; ++dy) {
                for (int dx = -radius; dx <= radius; ++dx) {
                    const int qx = x + dx, qy = y + dy;
                    if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
                    const float d = raw.meters[size_t(qy) * w + qx];
                    if (!measured(d, p)) continue;
                    const float diff = d - centre;
                    const float weight = std::exp(float(dx * dx + dy * dy) * spatial + diff * diff * range);
                    sum += weight * d;
                    weights += weight;
                }
            }
            out[size_t(y) * w + x] = sum / weights;
        }
    }
    return out;
}

std::vector<float> downsampleDepth(const std::vector<float>& fine, int fineWidth, int width, int height, const gpu::TrackParamsGpu& p) {
    std::vector<float> out(size_t(width) * height, 0.0f);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            float samples[4];
            for (int k = 0; k < 4; ++k) samples[k] = fine[size_t(2 * y + (k >> 1)) * fineWidth + 2 * x + (k & 1)];
            float reference = 0.0f;
            for (float s : samples)
                if (reference == 0.0f && s > 0.0f) reference = s;
            float sum = 0.0f, count = 0.0f;
            for (float s : samples)
                if (s > 0.0f && std::abs(s - reference) <= 3.0f * p.filterDepthSigma) sum += s, count += 1.0f;
            out[size_t(y) * width + x] = count > 0.0f ? sum / count : 0.0f;
        }
    }
    return out;
}

void pointsAndNormals(TrackingLevel& level, const gpu::TrackParamsGpu& p) {
    const int w = level.width, h = level.height;
    level.points.assign(size_t(w) * h, Eigen::Vector4f::Zero());
    level.normals.assign(size_t(w) * h, Eigen::Vector4f::Zero());
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            const float d = level.depth[i];
            if (d <= 0.0f) continue;
            const Eigen::Vector3f pt = backProject(x, y, d, level.intrinsics);
            level.points[i] << pt, 1.0f;
            if (x + 1 >= w || y + 1 >= h) continue;
            const float right = level.depth[i + 1], down = level.depth[i + w];
            const float jump = p.edgeJumpFraction * d;
            if (!(right > 0.0f && down > 0.0f && std::abs(right - d) <= jump && std::abs(down - d) <= jump)) continue;
            Eigen::Vector3f n = (backProject(x + 1, y, right, level.intrinsics) - pt).cross(backProject(x, y + 1, down, level.intrinsics) - pt);
            const float length2 = n.dot(n);
            if (!(length2 > 0.0f)) continue;
            n /= std::sqrt(length2);
            if (n.dot(pt) > 0.0f) n = -n;
            level.normals[i] << n, 1.0f;
        }
    }
}

// Adds w J^T J and w J^T r of one residual r with J = [jr, jt] (each product formed in float, as on the GPU).
void addTerm(IcpSums& sums, const Eigen::Vector3f& jr, const Eigen::Vector3f& jt, float r, float weight) {
    const float J[6] = {jr.x(), jr.y(), jr.z(), jt.x(), jt.y(), jt.z()};
    uint32_t slot = gpu::TRACK_SUM_JTJ;
    for (int a = 0; a < 6; ++a) {
        const float wa = weight * J[a];
        for (int b = a; b < 6; ++b) sums[slot++] += double(wa * J[b]);
        sums[gpu::TRACK_SUM_JTR + a] += double(wa * r);
    }
}

}  // namespace

std::vector<TrackingLevel> referenceTrackingPyramid(const DepthImage& depth, const Intrinsics& intrinsics, const gpu::TrackParamsGpu& params) {
    std::vector<TrackingLevel> levels(gpu::TRACK_LEVELS);
    Intrinsics k = intrinsics;
    k.width = depth.width, k.height = depth.height;
    for (int l = 0; l < int(gpu::TRACK_LEVELS); ++l) {
        TrackingLevel& level = levels[l];
        level.intrinsics = pyramidLevelIntrinsics(k, l);
        level.width = depth.width >> l;
        level.height = depth.height >> l;
        level.depth = l == 0 ? filterDepth(depth, params)
                             : downsampleDepth(levels[l - 1].depth, levels[l - 1].width, level.width, level.height, params);
        pointsAndNormals(level, params);
    }
    return levels;
}

void referenceDownsampleModel(const std::vector<Eigen::Vector4f>& positions, const std::vector<Eigen::Vector4f>& normals, int width,
                              int height, const gpu::TrackParamsGpu& params, std::vector<Eigen::Vector4f>& coarsePositions,
                              std::vector<Eigen::Vector4f>& coarseNormals) {
    const int cw = width >> 1, ch = height >> 1;
    coarsePositions.assign(size_t(cw) * ch, Eigen::Vector4f::Zero());
    coarseNormals.assign(size_t(cw) * ch, Eigen::Vector4f::Zero());
    for (int y = 0; y < ch; ++y) {
        for (int x = 0; x < cw; ++x) {
            size_t fine[4];
            for (int k = 0; k < 4; ++k) fine[k] = size_t(2 * y + (k >> 1)) * width + 2 * x + (k & 1);
            Eigen::Vector4f reference = Eigen::Vector4f::Zero();
            for (size_t f : fine)
                if (reference.w() == 0.0f && positions[f].w() != 0.0f) reference = positions[f];
            Eigen::Vector3f position = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::Zero();
            float count = 0.0f;
            for (size_t f : fine) {
                if (positions[f].w() == 0.0f || (positions[f].head<3>() - reference.head<3>()).norm() > params.modelMergeDistance) continue;
                position += positions[f].head<3>();
                normal += normals[f].head<3>();
                count += 1.0f;
            }
            const float length2 = normal.dot(normal);
            if (count == 0.0f || length2 <= 0.0f) continue;
            coarsePositions[size_t(y) * cw + x] << position / count, 1.0f;
            coarseNormals[size_t(y) * cw + x] << normal / std::sqrt(length2), 1.0f;
        }
    }
}

IcpSums referenceIcpSums(const TrackingLevel& frame, const std::vector<Eigen::Vector4f>& modelPositions,
                         const std::vector<Eigen::Vector4f>& modelNormals, const Pose& estimate, const Pose& modelPose,
                         const IcpGates& gates, const PhotometricLevel& photometric, bool checkerboard) {
    using namespace gpu;
    IcpSums sums{};
    const RigidRows toWorld = rigidRows(estimate), toModel = rigidRows(inverseRigid(modelPose));
    const Intrinsics& k = frame.intrinsics;
    const int w = frame.width, h = frame.height;
    for (size_t i = 0; i < frame.points.size(); ++i) {
        if (checkerboard && (i % size_t(w) + i / size_t(w)) % 2 != 0) continue;   // TRACK_FLAG_CHECKERBOARD
        const Eigen::Vector4f& point = frame.points[i];
        const Eigen::Vector4f& normal = frame.normals[i];
        if (point.w() == 0.0f || normal.w() == 0.0f) continue;
        sums[TRACK_SUM_VALID] += 1;
        const Eigen::Vector3f world = toWorld.apply(point.head<3>());
        const Eigen::Vector3f model = toModel.apply(world);
        if (!(model.z() > 0.0f)) continue;
        const float u = k.fx * (model.x() / model.z()) + k.cx;
        const float v = k.fy * (model.y() / model.z()) + k.cy;
        const float fu = std::floor(u + 0.5f), fv = std::floor(v + 0.5f);
        if (!(fu >= 0.0f && fv >= 0.0f && fu < float(w) && fv < float(h))) continue;
        const size_t m = size_t(fv) * w + size_t(fu);
        const Eigen::Vector4f& q = modelPositions[m];
        if (q.w() == 0.0f) continue;
        sums[TRACK_SUM_MODEL_HITS] += 1;
        const Eigen::Vector3f n = modelNormals[m].head<3>();
        const Eigen::Vector3f diff = world - q.head<3>();
        if (diff.dot(diff) > gates.distance * gates.distance) continue;
        if (rotate(toWorld, normal.head<3>()).dot(n) < gates.normalCos) continue;
        const float r = n.dot(diff);
        const float weight = std::abs(r) <= gates.huber ? 1.0f : gates.huber / std::abs(r);
        const Eigen::Vector3f centre(toWorld.r[0][3], toWorld.r[1][3], toWorld.r[2][3]);
        const Eigen::Vector3f lever = world - centre;
        addTerm(sums, lever.cross(n), n, r, weight);
        sums[TRACK_SUM_WEIGHTED_ERROR] += double(weight * r * r);
        sums[TRACK_SUM_INLIERS] += 1;
        sums[TRACK_SUM_SQUARED_ERROR] += double(r * r);

        // The photometric term (track_icp_reduce.comp): bilinear model intensity at (u, v) minus the frame's.
        if (!(photometric.weight > 0.0f) || !photometric.frame || !photometric.model) continue;
        const float frameIntensity = (*photometric.frame)[i];
        const float x0 = std::floor(u), y0 = std::floor(v);
        if (!(frameIntensity >= 0.0f && x0 >= 0.0f && y0 >= 0.0f && x0 + 1.0f < float(w) && y0 + 1.0f < float(h))) continue;
        const size_t corner = size_t(y0) * w + size_t(x0);
        const std::vector<float>& mi = *photometric.model;
        const float i00 = mi[corner], i10 = mi[corner + 1], i01 = mi[corner + w], i11 = mi[corner + w + 1];
        if (std::min(std::min(i00, i10), std::min(i01, i11)) < 0.0f) continue;
        const float tx = u - x0, ty = v - y0;
        const float top = i00 + tx * (i10 - i00), bottom = i01 + tx * (i11 - i01);
        const float rc = top + ty * (bottom - top) - frameIntensity;
        const float gx = (i10 - i00) + ty * ((i11 - i01) - (i10 - i00)), gy = bottom - top;
        const float iz = 1.0f / model.z();
        const Eigen::Vector3f gradCamera(gx * k.fx * iz, gy * k.fy * iz, -(gx * k.fx * model.x() + gy * k.fy * model.y()) * iz * iz);
        Eigen::Vector3f a;   // R^T gradCamera with R the model camera's world-to-camera rotation
        for (int c = 0; c < 3; ++c) a[c] = toModel.r[0][c] * gradCamera.x() + toModel.r[1][c] * gradCamera.y() + toModel.r[2][c] * gradCamera.z();
        const float wc = photometric.weight * (std::abs(rc) <= photometric.huber ? 1.0f : photometric.huber / std::abs(rc));
        addTerm(sums, lever.cross(a), a, rc, wc);
        sums[TRACK_SUM_WEIGHTED_ERROR] += double(wc * rc * rc);
    }
    return sums;
}

double referenceBlockViewSlack(const Eigen::Vector3i& block, double blockSide, const Pose& cameraToWorld, const Intrinsics& intrinsics,
                               int width, int height, double nearDepth, double farDepth) {
    const Eigen::Vector3d centre = (block.cast<double>() + Eigen::Vector3d::Constant(0.5)) * blockSide;
    const Eigen::Matrix4d worldToCamera = cameraToWorld.inverse();
    const Eigen::Vector3d c = worldToCamera.block<3, 3>(0, 0) * centre + worldToCamera.block<3, 1>(0, 3);
    const double r = 0.5 * blockSide * std::sqrt(3.0) * 1.01 + 1e-6;   // as ModelViewStage::record
    // The planes through the optical centre: u = fx x / z + cx within [-1.5, size + 0.5] (a pixel beyond the
    // framebuffer's [-0.5, size - 0.5]), as signed distances (a, b) . (along, z) / |(a, b)|.
    auto plane = [](double along, double z, double a, double b) { return (a * along + b * z) / std::sqrt(a * a + b * b); };
    const double fx = intrinsics.fx, fy = intrinsics.fy, cx = intrinsics.cx, cy = intrinsics.cy, lo = -1.5;
    const double distances[6] = {c.z() - nearDepth, farDepth - c.z(), plane(c.x(), c.z(), fx, cx - lo), plane(c.x(), c.z(), -fx, width + 0.5 - cx),
                                 plane(c.y(), c.z(), fy, cy - lo), plane(c.y(), c.z(), -fy, height + 0.5 - cy)};
    double slack = std::numeric_limits<double>::infinity();
    for (double d : distances) slack = std::min(slack, d + r);
    return slack;
}

}  // namespace vkmesh::cpu
