// Internal to evaluate.h's implementation (src/eval/evaluate.cpp, point_index.cpp, visibility.cpp,
// color_error.cpp): the parallel loop, number formatting and finiteness check those files share. Not API.
#pragma once

#include "core/types.h"

#include <Eigen/Core>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace vkmesh::eval::detail {

inline unsigned threadCount() {
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

inline std::string number(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

inline void checkFinite(const std::vector<Eigen::Vector3f>& points, const char* what) {
    for (size_t i = 0; i < points.size(); ++i)
        if (!points[i].allFinite())
            throw Error(std::string(what) + " point " + std::to_string(i) + " is not finite");
}

}  // namespace vkmesh::eval::detail
