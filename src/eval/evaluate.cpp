#include "eval/evaluate.h"

#include "io/dataset.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <thread>

namespace vkmesh::eval {
namespace {

unsigned threadCount() {
    const unsigned hw = std::thread::hardware_concurrency();
    return std::clamp(hw, 1u, 16u);
}

// Calls body(begin, end) on chunks of [0, n) from all hardware threads (dynamic, so uneven work balances).
template <class Body>
void parallelChunks(size_t n, size_t chunk, Body body) {
    const unsigned threads = static_cast<unsigned>(std::min<size_t>(threadCount(), (n + chunk - 1) / std::max<size_t>(chunk, 1)));
    if (threads <= 1) {
        if (n) body(size_t(0), n);
        return;
    }
    std::atomic<size_t> next{0};
    auto work = [&] {
        for (;;) {
            const size_t begin = next.fetch_add(chunk);
            if (begin >= n) return;
            body(begin, std::min(n, begin + chunk));
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
}

std::string number(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

void checkFinite(const std::vector<Eigen::Vector3f>& points, const char* what) {
    for (size_t i = 0; i < points.size(); ++i)
        if (!points[i].allFinite())
            throw Error(std::string(what) + " point " + std::to_string(i) + " is not finite");
}

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

namespace {
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

// ---------------------------------------------------------------------------------------------------------
// Colour

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
