// Colour error (MAE per channel, PSNR): ColorErrorSum, and a mesh's colours against coloured GT points or
// against a dataset's colour frames.
#include "eval/evaluate.h"
#include "eval/evaluate_internal.h"

#include "io/dataset.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace vkmesh::eval {

using detail::number;
using detail::parallelChunks;

void ColorErrorSum::add(const uint8_t* a, const uint8_t* b) {
    for (int c = 0; c < 3; ++c) {
        const double d = double(a[c]) - double(b[c]);
        absolute_[c] += std::abs(d);
        squared_ += d * d;
    }
    ++pairs_;
}

void ColorErrorSum::add(const std::array<uint8_t, 3>& a, const std::array<uint8_t, 3>& b) { add(a.data(), b.data()); }

void ColorErrorSum::merge(const ColorErrorSum& o) {
    pairs_ += o.pairs_;
    for (int c = 0; c < 3; ++c) absolute_[c] += o.absolute_[c];
    squared_ += o.squared_;
}

ColorError ColorErrorSum::result() const {
    ColorError e;
    e.pairs = pairs_;
    if (pairs_ == 0) return e;
    for (int c = 0; c < 3; ++c) e.mae[c] = absolute_[c] / double(pairs_);
    e.maeMean = (e.mae[0] + e.mae[1] + e.mae[2]) / 3;
    const double mse = squared_ / (3.0 * double(pairs_));
    e.psnr = mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
    return e;
}

ColorError colorErrorAgainstGt(const Mesh& mesh, const std::vector<Eigen::Vector3f>& gtPoints,
                               const std::vector<std::array<uint8_t, 3>>& gtColors, const std::vector<bool>& seen,
                               double maxDistance) {
    if (mesh.colors.size() != mesh.positions.size() || mesh.colors.empty())
        throw Error("colour error: the mesh has " + std::to_string(mesh.colors.size()) + " colours for " +
                    std::to_string(mesh.positions.size()) + " vertices");
    if (gtColors.size() != gtPoints.size())
        throw Error("colour error: the ground truth has " + std::to_string(gtColors.size()) + " colours for " +
                    std::to_string(gtPoints.size()) + " points");
    if (!seen.empty() && seen.size() != gtPoints.size())
        throw Error("colour error: seen mask of " + std::to_string(seen.size()) + " for " +
                    std::to_string(gtPoints.size()) + " GT points");
    std::vector<Eigen::Vector3f> queries;
    std::vector<size_t> which;
    for (size_t i = 0; i < gtPoints.size(); ++i)
        if (seen.empty() || seen[i]) {
            queries.push_back(gtPoints[i]);
            which.push_back(i);
        }
    const std::vector<uint32_t> nearest = nearestIndices(mesh.positions, queries, maxDistance);
    ColorErrorSum sum;
    for (size_t q = 0; q < queries.size(); ++q)
        if (nearest[q] != UINT32_MAX) sum.add(mesh.colors[nearest[q]], gtColors[which[q]]);
    return sum.result();
}

ColorError colorErrorAgainstFrames(const Mesh& mesh, const Dataset& dataset, size_t every, double depthTolerance,
                                   std::vector<std::string>* warnings, size_t* framesUsed) {
    if (mesh.colors.size() != mesh.positions.size() || mesh.colors.empty())
        throw Error("colour error: the mesh has " + std::to_string(mesh.colors.size()) + " colours for " +
                    std::to_string(mesh.positions.size()) + " vertices");
    if (every == 0) throw Error("colour error: every must be at least 1");
    if (!(std::isfinite(depthTolerance) && depthTolerance > 0))
        throw Error("colour error: depth tolerance " + number(depthTolerance) + " must be positive and finite");
    const Intrinsics& k = dataset.intrinsics();
    std::vector<size_t> frames;
    for (size_t i = 0; i < dataset.size(); i += every) frames.push_back(i);
    std::vector<ColorErrorSum> sums(frames.size());
    std::vector<std::string> notes(frames.size());
    // One frame per task: loading the images dominates, and each frame's sum is its own.
    parallelChunks(frames.size(), 1, [&](size_t b, size_t e) {
        for (size_t j = b; j < e; ++j) {
            const size_t f = frames[j];
            std::string why;
            const ColorImage color = dataset.loadColor(f, &why);
            if (color.empty()) {
                notes[j] = why.empty() ? "frame " + std::to_string(f) + " has no colour image; not compared" : why;
                continue;
            }
            DepthImage depth;
            try {
                depth = dataset.loadDepth(f);
            } catch (const Error& error) {
                notes[j] = std::string(error.what()) + "; frame " + std::to_string(f) + " not compared";
                continue;
            }
            const Pose& c2w = dataset.frame(f).cameraToWorld;
            const Eigen::Matrix3d rt = c2w.topLeftCorner<3, 3>().transpose();
            const Eigen::Vector3d t = -rt * c2w.topRightCorner<3, 1>();
            for (size_t v = 0; v < mesh.positions.size(); ++v) {
                const Eigen::Vector3d p = rt * mesh.positions[v].cast<double>() + t;
                if (!(p.z() > 0)) continue;
                const long u = std::lround(k.fx * p.x() / p.z() + k.cx), w = std::lround(k.fy * p.y() / p.z() + k.cy);
                if (u < 0 || w < 0 || u >= depth.width || w >= depth.height) continue;
                const float d = depth.at(int(u), int(w));
                if (!(d > 0) || std::abs(p.z() - d) >= depthTolerance) continue;
                sums[j].add(mesh.colors[v].data(), color.at(int(u), int(w)));
            }
        }
    });
    ColorErrorSum total;
    size_t used = 0;
    for (size_t j = 0; j < frames.size(); ++j) {
        if (!notes[j].empty()) {
            if (warnings) warnings->push_back(notes[j]);
            continue;
        }
        ++used;
        total.merge(sums[j]);
    }
    if (framesUsed) *framesUsed = used;
    return total.result();
}

}  // namespace vkmesh::eval
