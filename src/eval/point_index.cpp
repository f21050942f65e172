// The exact capped nearest-neighbour index (a dense point grid with a distance transform of its occupied
// cells) and the searches that use it: nearestDistances, nearestIndices.
#include "eval/evaluate.h"
#include "eval/evaluate_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace vkmesh::eval {

using detail::checkFinite;
using detail::number;
using detail::parallelChunks;

namespace {

// Exact capped nearest-neighbour search on a dense uniform grid over the points' bounding box, padded by
// enough cells (pad_) that a query outside the grid is farther than maxDistance from every point. Points are
// sorted by cell (x fastest). A query scans the cells around its own ring by ring (ring r: the cells at
// Chebyshev distance r), nearest slabs, rows and cells first, skipping every cell farther than the best
// distance so far, and stops when the next ring cannot hold anything nearer. dist_[c] is the Chebyshev
// distance (in cells, capped at K_ = pad_ + 1) from cell c to the nearest occupied cell: rings closer than
// that are empty and skipped, and a query K_ or more cells from any occupied cell is at least
// pad_ * h >= maxDistance away and answered at once.
class PointGrid {
public:
    PointGrid(const std::vector<Eigen::Vector3f>& points, double maxDistance) : maxDistance_(float(maxDistance)) {
        if (points.empty()) return;
        Eigen::Vector3d lo = points[0].cast<double>(), hi = lo;
        for (const auto& p : points) {
            lo = lo.cwiseMin(p.cast<double>());
            hi = hi.cwiseMax(p.cast<double>());
        }
        const double extent = (hi - lo).maxCoeff();
        // ~2 cm cells: a surface sampled every 5 mm puts ~16 points in a cell it crosses. Coarser when the
        // dense grid would hold more than 32 million cells (a large scene), and at least maxDistance / 31
        // so that the distance transform (whose cost grows with pad_) stays cheap.
        const double kMaxCells = double(1u << 25);
        double h = std::min(0.02, maxDistance);
        h = std::max({h, maxDistance / 31.0, extent / 4096.0});
        for (;;) {
            pad_ = int(std::ceil(maxDistance / h));
            double cells = 1;
            for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo[a]) / h) + 1 + 2 * pad_;
            if (cells <= kMaxCells) break;
            h *= 1.25;
        }
        h_ = h;
        K_ = pad_ + 1;  // <= 32
        origin_ = lo - Eigen::Vector3d::Constant(pad_ * h);
        for (int a = 0; a < 3; ++a) n_[a] = int(std::floor((hi[a] - lo[a]) / h)) + 1 + 2 * pad_;
        const size_t cellCount = size_t(n_[0]) * n_[1] * n_[2];

        // Counting sort of the points by cell.
        std::vector<uint32_t> cellOf(points.size());
        start_.assign(cellCount + 1, 0);
        for (size_t i = 0; i < points.size(); ++i) {
            int c[3];
            for (int a = 0; a < 3; ++a)
                c[a] = std::clamp(int(std::floor((points[i][a] - origin_[a]) / h_)), 0, n_[a] - 1);
            cellOf[i] = uint32_t(index(c[0], c[1], c[2]));
            ++start_[cellOf[i] + 1];
        }
        for (size_t c = 0; c < cellCount; ++c) start_[c + 1] += start_[c];
        sorted_.resize(points.size());
        {
            std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
            originalIndex_.resize(points.size());
            for (size_t i = 0; i < points.size(); ++i) {
                originalIndex_[fill[cellOf[i]]] = uint32_t(i);
                sorted_[fill[cellOf[i]]++] = points[i];
            }
        }
        buildDistanceTransform();
    }

    // Distance to the nearest point, capped at maxDistance; with `index`, that point's index in the
    // constructor's `points` (UINT32_MAX when none lies strictly within maxDistance).
    float nearest(const Eigen::Vector3f& q, uint32_t* index = nullptr) const {
        if (index) *index = UINT32_MAX;
        if (sorted_.empty()) return maxDistance_;
        Query query{q, {}, {}, maxDistance_ * maxDistance_, 1.0 / (h_ * h_)};
        const float result = search(query);
        if (index && query.bestSorted != UINT32_MAX) *index = originalIndex_[query.bestSorted];
        return result;
    }

private:
    struct Query {
        Eigen::Vector3f q;
        double local[3];  // position in cell units from the grid origin
        int cell[3];
        float best2;      // squared best distance so far (metres)
        double inv2;      // 1 / h^2
        uint32_t bestSorted = UINT32_MAX;  // the point at best2, in sorted_ order
        bool farther(double gapCells2) const { return gapCells2 >= best2 * inv2; }
    };

    float search(Query& query) const {
        const Eigen::Vector3f& q = query.q;
        for (int a = 0; a < 3; ++a) {
            query.local[a] = (double(q[a]) - origin_[a]) / h_;
            if (!(query.local[a] >= 0 && query.local[a] < n_[a])) return maxDistance_;  // >= pad_ * h away
            query.cell[a] = int(query.local[a]);
        }
        const int k0 = dist_[index(query.cell[0], query.cell[1], query.cell[2])];
        if (k0 >= K_) return maxDistance_;
        for (int r = k0;; ++r) {
            if (r > 0) {
                // Ring r lies outside the box of rings 0 .. r-1: no point in it is nearer than that box's wall.
                double wall = std::numeric_limits<double>::max();
                for (int a = 0; a < 3; ++a)
                    wall = std::min({wall, query.local[a] - (query.cell[a] - (r - 1)), (query.cell[a] + r) - query.local[a]});
                if (wall * wall >= query.best2 * query.inv2) break;
            }
            bool inside = false;
            for (int a = 0; a < 3; ++a) inside |= query.cell[a] - r >= 0 || query.cell[a] + r < n_[a];
            if (!inside) break;  // the ring is entirely outside the grid, and so are all later ones
            scanRing(query, r);
        }
        return std::min(std::sqrt(query.best2), maxDistance_);
    }

    size_t index(int x, int y, int z) const { return (size_t(z) * n_[1] + y) * n_[0] + x; }

    // Distance in cells from a coordinate to the cell [i, i + 1) along one axis.
    static double gap(double l, int i) { return std::max({0.0, i - l, l - (i + 1)}); }

    void scanCell(Query& query, size_t cell) const {
        for (uint32_t i = start_[cell], e = start_[cell + 1]; i < e; ++i) {
            const float d2 = (sorted_[i] - query.q).squaredNorm();
            if (d2 < query.best2) query.best2 = d2, query.bestSorted = i;
        }
    }

    // Cells x0 .. x1 of row (y, z), from the one nearest the query outwards on each side, until they are
    // farther than the best distance so far.
    void scanRow(Query& query, int x0, int x1, int y, int z, double gyz2) const {
        const size_t row = index(0, y, z);
        const int xm = std::clamp(query.cell[0], x0, x1);
        for (int x = xm; x <= x1; ++x) {
            const double g = gap(query.local[0], x);
            if (query.farther(gyz2 + g * g)) break;
            scanCell(query, row + x);
        }
        for (int x = xm - 1; x >= x0; --x) {
            const double g = gap(query.local[0], x);
            if (query.farther(gyz2 + g * g)) break;
            scanCell(query, row + x);
        }
    }

    // The cells at Chebyshev distance r from the query's cell, slabs and rows nearest the query first.
    void scanRing(Query& query, int r) const {
        const int* c = query.cell;
        const int x0 = std::max(c[0] - r, 0), x1 = std::min(c[0] + r, n_[0] - 1);
        for (int dz = 0; dz <= r; ++dz)
            for (int sz = (dz ? -1 : 1); sz <= 1; sz += 2) {
                const int z = c[2] + sz * dz;
                if (z < 0 || z >= n_[2]) continue;
                const double gz = gap(query.local[2], z);
                if (query.farther(gz * gz)) continue;
                for (int dy = 0; dy <= r; ++dy)
                    for (int sy = (dy ? -1 : 1); sy <= 1; sy += 2) {
                        const int y = c[1] + sy * dy;
                        if (y < 0 || y >= n_[1]) continue;
                        const double gy = gap(query.local[1], y), gyz2 = gz * gz + gy * gy;
                        if (query.farther(gyz2)) continue;
                        if (dz == r || dy == r) {
                            scanRow(query, x0, x1, y, z, gyz2);
                        } else {
                            // Inside the ring's box only the two end cells of the row belong to ring r.
                            if (c[0] - r >= 0) scanRow(query, c[0] - r, c[0] - r, y, z, gyz2);
                            if (r > 0 && c[0] + r < n_[0]) scanRow(query, c[0] + r, c[0] + r, y, z, gyz2);
                        }
                    }
            }
    }

    // Capped Chebyshev distance transform, separable: along x by two sweeps, then along y and z as
    // out(i) = min over |d| < K of max(|d|, in(i + d)) (values >= K mean "K or more").
    void buildDistanceTransform() {
        const size_t cellCount = size_t(n_[0]) * n_[1] * n_[2];
        const uint8_t cap = uint8_t(K_);
        dist_.assign(cellCount, cap);
        const int nx = n_[0], ny = n_[1], nz = n_[2];
        for (int z = 0; z < nz; ++z)
            for (int y = 0; y < ny; ++y) {
                const size_t row = index(0, y, z);
                int d = K_;
                for (int x = 0; x < nx; ++x) {
                    d = start_[row + x + 1] > start_[row + x] ? 0 : std::min(d + 1, K_);
                    dist_[row + x] = uint8_t(d);
                }
                d = K_;
                for (int x = nx - 1; x >= 0; --x) {
                    d = dist_[row + x] == 0 ? 0 : std::min(d + 1, K_);
                    dist_[row + x] = std::min(dist_[row + x], uint8_t(d));
                }
            }
        std::vector<uint8_t> out(cellCount);
        // Along y (stride nx) within each z slab, then along z (stride nx * ny).
        auto pass = [&](int count, size_t stride, size_t lineCount, auto lineBase) {
            parallelChunks(lineCount, 1, [&](size_t begin, size_t end) {
                for (size_t l = begin; l < end; ++l) {
                    const size_t base = lineBase(l);
                    for (int i = 0; i < count; ++i) {
                        uint8_t* o = &out[base + i * stride];
                        std::fill(o, o + nx, cap);
                        const int d0 = std::max(-(K_ - 1), -i), d1 = std::min(K_ - 1, count - 1 - i);
                        for (int d = d0; d <= d1; ++d) {
                            const uint8_t ad = uint8_t(std::abs(d));
                            const uint8_t* in = &dist_[base + (i + d) * stride];
                            for (int x = 0; x < nx; ++x) o[x] = std::min(o[x], std::max(ad, in[x]));
                        }
                    }
                }
            });
            dist_.swap(out);
        };
        pass(ny, size_t(nx), size_t(nz), [&](size_t z) { return index(0, 0, int(z)); });
        // Along z: each "line" is one y row, all z, the x run vectorised.
        pass(nz, size_t(nx) * ny, size_t(ny), [&](size_t y) { return index(0, int(y), 0); });
    }

    float maxDistance_;
    double h_ = 1;
    int pad_ = 0, K_ = 1;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    int n_[3] = {0, 0, 0};
    std::vector<uint32_t> start_;
    std::vector<Eigen::Vector3f> sorted_;
    std::vector<uint32_t> originalIndex_;  // sorted_[i] is points[originalIndex_[i]]
    std::vector<uint8_t> dist_;
};

// The checks nearestDistances and nearestIndices share, and the grid they search.
PointGrid checkedGrid(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& queries,
                      double maxDistance) {
    if (!(std::isfinite(maxDistance) && maxDistance > 0))
        throw Error("max distance " + number(maxDistance) + " must be positive and finite");
    checkFinite(points, "indexed");
    checkFinite(queries, "query");
    return PointGrid(points, maxDistance);
}

}  // namespace

std::vector<float> nearestDistances(const std::vector<Eigen::Vector3f>& points,
                                    const std::vector<Eigen::Vector3f>& queries, double maxDistance) {
    const PointGrid grid = checkedGrid(points, queries, maxDistance);
    std::vector<float> out(queries.size());
    parallelChunks(queries.size(), 4096, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) out[i] = grid.nearest(queries[i]);
    });
    return out;
}

std::vector<uint32_t> nearestIndices(const std::vector<Eigen::Vector3f>& points,
                                     const std::vector<Eigen::Vector3f>& queries, double maxDistance) {
    const PointGrid grid = checkedGrid(points, queries, maxDistance);
    std::vector<uint32_t> out(queries.size());
    parallelChunks(queries.size(), 4096, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) grid.nearest(queries[i], &out[i]);
    });
    return out;
}

}  // namespace vkmesh::eval
