// Quality of a reconstruction against ground truth, the way the field measures it (Knapitsch et al. 2017,
// Tanks and Temples; the ICL-NUIM surface evaluation): both surfaces are turned into point sets, and
//   accuracy      = distance of each reconstruction sample to the nearest GT point   (mean, median),
//   completeness  = distance of each GT point to the nearest reconstruction sample   (mean, median),
//   precision(t)  = share of reconstruction samples within t of the GT,
//   recall(t)     = share of GT points within t of the reconstruction,
//   F(t)          = 2 P R / (P + R)   (0 when P + R = 0),
// at thresholds t (default 1, 2 and 5 cm). "Within t" means distance < t.
//
// Conventions that make numbers comparable between methods:
//   * a mesh is sampled BY AREA (sampleByArea), never by vertex, so a method that writes many small or
//     duplicated vertices is neither rewarded nor punished for it; a point cloud is used as it is;
//   * every method is held to the same GT set: completeness and recall are of the part of the GT surface
//     the sequence saw (seenMask); accuracy and precision are against the whole GT surface (see evaluate());
//   * distances are point-to-point and capped at EvalOptions::maxDistance (default 20 cm) before the means
//     and medians are taken, so a few stray far-away samples cannot dominate them; a capped distance reads
//     "maxDistance or more". Point-to-point distances to a GT sampled every s metres have a floor of about
//     0.4 s for a perfect surface (~2 mm at s = 5 mm): compare methods on the same GT, or sample it denser.
#pragma once

#include "core/types.h"
#include "io/ply.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vkmesh {
class Dataset;
}

namespace vkmesh::eval {

struct EvalOptions {
    std::vector<double> thresholds{0.01, 0.02, 0.05};  // metres; each in (0, maxDistance]
    double sampleSpacing = 0.005;  // metres: a mesh gets about one sample per sampleSpacing^2 of area
    uint32_t seed = 1;             // of the area sampling (the same seed gives the same samples)
    // Nearest-neighbour distances are capped here (metres): means and medians are taken over the capped
    // distances, and a point with nothing within maxDistance counts as maxDistance away.
    double maxDistance = 0.2;
};

struct ThresholdScores {
    double threshold = 0, precision = 0, recall = 0, fscore = 0;
};

struct EvalResult {
    size_t reconstructionSamples = 0;  // points of the reconstruction that were evaluated
    size_t gtPoints = 0;               // GT points in the GT file (evaluate() sets it to gt.size())
    size_t gtPointsSeen = 0;           // GT points evaluated: those the sequence saw (evaluate(): gt.size())
    double accuracyMean = 0, accuracyMedian = 0;          // metres, reconstruction -> GT, capped
    double completenessMean = 0, completenessMedian = 0;  // metres, GT -> reconstruction, capped
    std::vector<ThresholdScores> scores;                  // one per EvalOptions::thresholds, same order
};

// Uniform random points on the surface of `mesh`: every triangle gets floor(area / spacing^2) samples plus
// one more with probability equal to the fractional part, each uniformly distributed on the triangle, so the
// expected density is exactly one sample per spacing^2 everywhere. Deterministic for a given seed.
// Triangles with a non-finite vertex are skipped. A mesh without triangles (a point cloud) is returned as it
// is. Throws Error for spacing <= 0 or non-finite, a vertex index out of range, or more than 200 million
// samples (the mesh is in other units than metres, or the spacing is too fine).
std::vector<Eigen::Vector3f> sampleByArea(const Mesh& mesh, double spacing, uint32_t seed);

// Which GT points the sequence saw. Point i counts as seen when, in at least one evaluated frame, it lies in
// front of the camera and projects inside the depth image where one of the (up to) 4 pixels whose centres
// surround the projection (centres at integer coordinates) holds a valid depth d with
// |z - d| < max(tolerance, 3 / depthScale), z the point's camera-frame depth: it was the visible surface
// there (a point hidden behind something nearer, or on the far side of an object, is not). Taking the 4
// pixels rather than the nearest one keeps surfaces seen at grazing angles from dropping out at low
// resolution. Frames 0, frameStride, 2 frameStride, ... are evaluated (frameStride 0 counts as 1); depth comes from
// Dataset::loadDepth, so the dataset's maxDepth applies. A frame whose depth cannot be read is skipped and
// reported in `warnings` when given. Runs on all hardware threads.
std::vector<bool> seenMask(const std::vector<Eigen::Vector3f>& gt, const Dataset& dataset, size_t frameStride = 1,
                           double tolerance = 0.02, std::vector<std::string>* warnings = nullptr);

// For every query, the distance to the nearest of `points`, capped at maxDistance (also when `points` is
// empty). Exact (not approximate): a dense uniform grid over the points' bounding box, cells of 2 cm (at
// least maxDistance / 31, and coarser when the grid would need more than 32 million cells), searched ring by
// ring from the query's cell, nearest cells first, with a capped Chebyshev distance transform of the occupied
// cells to skip empty space. Runs on all hardware threads. About 0.3 us per query near a 5 mm-sampled
// surface, ~1-3 us per query 5-15 cm away, instant beyond maxDistance.
// Throws Error for a non-finite or non-positive maxDistance or a non-finite point.
std::vector<float> nearestDistances(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<Eigen::Vector3f>& queries, double maxDistance);

// The metrics above for reconstruction samples against GT points, both directions against the same `gt`
// (e.g. already restricted to what was seen). gtPoints = gtPointsSeen = gt.size(). Throws Error when either
// set is empty or holds a non-finite point, or for bad options (maxDistance not positive and finite, a
// threshold outside (0, maxDistance]).
EvalResult evaluate(const std::vector<Eigen::Vector3f>& reconstruction, const std::vector<Eigen::Vector3f>& gt,
                    const EvalOptions& options = {});

// The same with a seen mask (what `vkmesh eval --dataset` uses): completeness and recall measure how much of
// the SEEN GT (seen[i]) the reconstruction covers, while accuracy and precision measure reconstruction
// samples against ALL of `gt` -- a reconstructed point is right when it lies on the true surface. So the
// mask's own limits (a frame stride, a surface seen only at grazing angles or through noise beyond the
// tolerance, which fusion may still reconstruct) cannot count correct geometry as error; every method
// is still held to the same seen set for completeness. gtPoints = gt.size(), gtPointsSeen = seen count.
// Throws Error as above, for a mask of another size than gt, or for a mask with nothing seen.
EvalResult evaluate(const std::vector<Eigen::Vector3f>& reconstruction, const std::vector<Eigen::Vector3f>& gt,
                    const std::vector<bool>& seen, const EvalOptions& options = {});

// For every query, the index of the nearest of `points` (ties: any one of them), or UINT32_MAX when none lies
// within maxDistance. The same search and errors as nearestDistances.
std::vector<uint32_t> nearestIndices(const std::vector<Eigen::Vector3f>& points,
                                     const std::vector<Eigen::Vector3f>& queries, double maxDistance);

// ---------------------------------------------------------------------------------------------------------
// Colour. Errors are per channel on the 0-255 scale, over the pairs (reconstructed colour, reference colour)
// a function compares:
//   mae[c]   mean |a - b| of channel c (red, green, blue); maeMean is their average;
//   psnr     10 log10(255^2 / MSE) dB, MSE over all three channels of all pairs; +infinity when every pair
//            is equal (JSON writes it as null), 0 pairs: 0.
struct ColorError {
    size_t pairs = 0;
    double mae[3] = {0, 0, 0};
    double maeMean = 0;
    double psnr = 0;
};

// Sums of colour differences, accumulated pair by pair and turned into a ColorError at the end.
class ColorErrorSum {
public:
    void add(const std::array<uint8_t, 3>& reconstructed, const std::array<uint8_t, 3>& reference);
    void add(const uint8_t* reconstructed, const uint8_t* reference);
    void merge(const ColorErrorSum& other);
    ColorError result() const;

private:
    size_t pairs_ = 0;
    double absolute_[3] = {0, 0, 0};
    double squared_ = 0;
};

// Colour of a mesh against coloured GT points: for every GT point with seen[i] (all when `seen` is empty)
// whose nearest mesh VERTEX lies within maxDistance (metres), that vertex's colour against the point's. GT
// points farther from the mesh are a completeness matter, not a colour one, and are left out. Throws Error
// when the colours are missing or not one per point, for a mask of another size, or a non-finite point.
ColorError colorErrorAgainstGt(const Mesh& mesh, const std::vector<Eigen::Vector3f>& gtPoints,
                               const std::vector<std::array<uint8_t, 3>>& gtColors, const std::vector<bool>& seen,
                               double maxDistance);

// Colour of a mesh against a dataset's own colour images (real data, no GT): frames 0, every, 2 every, ...
// Each mesh vertex the frame sees -- in front of the camera, projecting (nearest pixel) inside the image onto
// a valid depth d with |z - d| < depthTolerance, z its camera depth -- is compared with that pixel of the
// frame's colour image (Dataset::loadColor). Frames without usable colour or depth are skipped, the reason
// in `warnings`; framesUsed (when given) counts the others. Throws Error for a mesh without colours, every
// 0, or a tolerance that is not positive and finite.
ColorError colorErrorAgainstFrames(const Mesh& mesh, const Dataset& dataset, size_t every, double depthTolerance = 0.03,
                                   std::vector<std::string>* warnings = nullptr, size_t* framesUsed = nullptr);

}  // namespace vkmesh::eval
