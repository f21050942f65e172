// Accuracy, completeness and F-score of a reconstruction against GT points, and a mesh's area sampling (the
// point index, visibility mask and colour error are in point_index.cpp, visibility.cpp and color_error.cpp).
#include "eval/evaluate.h"
#include "eval/evaluate_internal.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace vkmesh::eval {

using detail::checkFinite;
using detail::number;

namespace {

double mean(const std::vector<float>& v) {
    double s = 0;
    for (float x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
}

double median(std::vector<float> v) {
    if (v.empty()) return 0;
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    double m = v[mid];
    if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
    return m;
}

double shareBelow(const std::vector<float>& v, double t) {
    size_t n = 0;
    for (float x : v) n += double(x) < t;
    return v.empty() ? 0.0 : double(n) / double(v.size());
}

// 53 random bits as a double in [0, 1): the same numbers on every standard library.
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

}  // namespace

std::vector<Eigen::Vector3f> sampleByArea(const Mesh& mesh, double spacing, uint32_t seed) {
    if (!(std::isfinite(spacing) && spacing > 0))
        throw Error("sample spacing " + number(spacing) + " must be positive and finite");
    if (mesh.triangles.empty()) return mesh.positions;
    const size_t nv = mesh.positions.size();
    const double perArea = 1.0 / (spacing * spacing);
    double expected = 0;
    std::vector<double> areas(mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        for (uint32_t v : tri)
            if (v >= nv)
                throw Error("mesh triangle " + std::to_string(t) + " uses vertex " + std::to_string(v) + " of " +
                            std::to_string(nv));
        const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>(), b = mesh.positions[tri[1]].cast<double>(),
                              c = mesh.positions[tri[2]].cast<double>();
        const double area = 0.5 * (b - a).cross(c - a).norm();
        areas[t] = std::isfinite(area) ? area : -1.0;
        if (areas[t] > 0) expected += area * perArea;
    }
    if (expected > 2e8)
        throw Error("sampling the mesh every " + number(spacing) + " m would take " + number(expected) +
                    " samples (more than 200 million): is the mesh in metres? Use a larger spacing");
    std::vector<Eigen::Vector3f> samples;
    samples.reserve(size_t(expected * 1.001) + 16);
    std::mt19937_64 rng(seed);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (!(areas[t] > 0)) continue;
        const double want = areas[t] * perArea;
        const double whole = std::floor(want);
        size_t count = size_t(whole) + (uniform01(rng) < want - whole ? 1 : 0);
        const auto& tri = mesh.triangles[t];
        const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>(), b = mesh.positions[tri[1]].cast<double>(),
                              c = mesh.positions[tri[2]].cast<double>();
        for (size_t k = 0; k < count; ++k) {
            // Uniform on the triangle: s = sqrt(r1) picks the distance from a, r2 the place across.
            const double s = std::sqrt(uniform01(rng)), r2 = uniform01(rng);
            samples.push_back(((1 - s) * a + s * (1 - r2) * b + s * r2 * c).cast<float>());
        }
    }
    return samples;
}

namespace {

// Accuracy and precision against `gtForAccuracy`, completeness and recall of `gtForCompleteness`.
EvalResult evaluateSets(const std::vector<Eigen::Vector3f>& reconstruction,
                        const std::vector<Eigen::Vector3f>& gtForAccuracy,
                        const std::vector<Eigen::Vector3f>& gtForCompleteness, const EvalOptions& options) {
    if (!(std::isfinite(options.maxDistance) && options.maxDistance > 0))
        throw Error("max distance " + number(options.maxDistance) + " must be positive and finite");
    for (double t : options.thresholds)
        if (!(std::isfinite(t) && t > 0 && t <= options.maxDistance))
            throw Error("threshold " + number(t) + " must be in (0, max distance " + number(options.maxDistance) + "]");
    if (reconstruction.empty()) throw Error("the reconstruction has no points to evaluate");
    if (gtForCompleteness.empty()) throw Error("the ground truth has no points to evaluate against");
    checkFinite(reconstruction, "reconstruction");
    checkFinite(gtForAccuracy, "ground-truth");
    if (&gtForCompleteness != &gtForAccuracy) checkFinite(gtForCompleteness, "ground-truth");

    const std::vector<float> toGt = nearestDistances(gtForAccuracy, reconstruction, options.maxDistance);
    const std::vector<float> toRec = nearestDistances(reconstruction, gtForCompleteness, options.maxDistance);

    EvalResult r;
    r.reconstructionSamples = reconstruction.size();
    r.gtPoints = gtForAccuracy.size();
    r.gtPointsSeen = gtForCompleteness.size();
    r.accuracyMean = mean(toGt);
    r.accuracyMedian = median(toGt);
    r.completenessMean = mean(toRec);
    r.completenessMedian = median(toRec);
    for (double t : options.thresholds) {
        ThresholdScores s;
        s.threshold = t;
        s.precision = shareBelow(toGt, t);
        s.recall = shareBelow(toRec, t);
        s.fscore = s.precision + s.recall > 0 ? 2 * s.precision * s.recall / (s.precision + s.recall) : 0.0;
        r.scores.push_back(s);
    }
    return r;
}

}  // namespace

EvalResult evaluate(const std::vector<Eigen::Vector3f>& reconstruction, const std::vector<Eigen::Vector3f>& gt,
                    const EvalOptions& options) {
    return evaluateSets(reconstruction, gt, gt, options);
}

EvalResult evaluate(const std::vector<Eigen::Vector3f>& reconstruction, const std::vector<Eigen::Vector3f>& gt,
                    const std::vector<bool>& seen, const EvalOptions& options) {
    if (seen.size() != gt.size())
        throw Error("seen mask of " + std::to_string(seen.size()) + " entries for " + std::to_string(gt.size()) +
                    " ground-truth points");
    std::vector<Eigen::Vector3f> seenPoints;
    for (size_t i = 0; i < gt.size(); ++i)
        if (seen[i]) seenPoints.push_back(gt[i]);
    if (seenPoints.empty() && !gt.empty()) throw Error("no ground-truth point is marked seen");
    return evaluateSets(reconstruction, gt, seenPoints, options);
}

}  // namespace vkmesh::eval
