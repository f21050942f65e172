// Bytes and milliseconds per frame of the frame store (core/frame_store.h) on real RGB-D sequences: the first N
// frames of each dataset folder (TUM layout: depth.txt and rgb.txt, depth PNGs uint16 / 5000, colour decoded to
// RGB8), stored depth only and with colour at several zstd levels, then read back and checked bit for bit.
// Prints, per dataset and level: raw and compressed bytes per frame for depth and colour, the depth PNGs' own
// size for comparison, and the mean add() and get() milliseconds per frame (one thread).
//
// Not part of the CMake build (it needs OpenCV, which vkmesh_base does not link). Build and run from the checkout:
//   g++ -std=c++20 -O2 -ffp-contract=off -Isrc -Ishaders_comp -isystem /usr/include/eigen3 -isystem /usr/include/opencv4
//       bench/frame_store_bytes.cpp src/core/frame_store.cpp src/core/map_format.cpp
//       -lzstd -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -o /tmp/frame_store_bytes
//   /tmp/frame_store_bytes [--frames 20] [--levels 1,3,9] ../shared/datasets/tum_fr1_rpy ../shared/datasets/iclnuim_office_traj0
#include "core/frame_store.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace vkmesh;
namespace fs = std::filesystem;

namespace {

// The file names of a TUM-style list (depth.txt, rgb.txt): "timestamp path" lines, '#' comments.
std::vector<std::pair<double, std::string>> listFile(const fs::path& file, size_t max) {
    std::ifstream in(file);
    if (!in) throw Error("cannot read " + file.string());
    std::vector<std::pair<double, std::string>> out;
    for (std::string line; out.size() < max && std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        double t;
        std::string path;
        if (s >> t >> path) out.emplace_back(t, path);
    }
    return out;
}

// As the dataset readers convert (io/datasets/image_decoding.cpp): float(raw / scale), 0 = no measurement.
DepthImage readDepth(const fs::path& file, double scale) {
    const cv::Mat raw = cv::imread(file.string(), cv::IMREAD_ANYDEPTH);
    if (raw.empty() || raw.type() != CV_16UC1) throw Error("not a 16-bit depth PNG: " + file.string());
    DepthImage d{raw.cols, raw.rows, std::vector<float>(size_t(raw.cols) * raw.rows)};
    for (int y = 0; y < raw.rows; ++y)
        for (int x = 0; x < raw.cols; ++x) {
            const uint16_t v = raw.at<uint16_t>(y, x);
            d.meters[size_t(y) * raw.cols + x] = v == 0 ? 0.0f : float(v / scale);
        }
    return d;
}

ColorImage readColor(const fs::path& file) {
    cv::Mat bgr = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (bgr.empty()) throw Error("cannot read colour image " + file.string());
    ColorImage c{bgr.cols, bgr.rows, std::vector<uint8_t>(size_t(bgr.cols) * bgr.rows * 3)};
    for (int y = 0; y < bgr.rows; ++y)
        for (int x = 0; x < bgr.cols; ++x) {
            const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
            uint8_t* q = &c.rgb[(size_t(y) * bgr.cols + x) * 3];
            q[0] = p[2], q[1] = p[1], q[2] = p[0];
        }
    return c;
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

struct Run {
    double bytesPerFrame = 0, addMs = 0, getMs = 0;
};

Run measureOnce(const std::vector<StoredFrame>& frames, int level) {
    FrameStoreOptions options;
    options.zstdLevel = level;
    FrameStore store(options);
    auto t0 = std::chrono::steady_clock::now();
    for (const StoredFrame& f : frames) store.add(f);
    const double addMs = msSince(t0);
    t0 = std::chrono::steady_clock::now();
    for (const StoredFrame& f : frames) {
        const StoredFrame back = store.get(f.index);
        if (std::memcmp(back.depth.meters.data(), f.depth.meters.data(), 4 * f.depth.meters.size()) != 0 || back.color.rgb != f.color.rgb)
            throw Error("frame " + std::to_string(f.index) + " did not come back bit for bit");
    }
    const double getMs = msSince(t0);
    const double n = double(frames.size());
    return {double(store.stats().compressedBytes) / n, addMs / n, getMs / n};
}

// The best of three runs: the times of a busy machine vary by tens of percent.
Run measure(const std::vector<StoredFrame>& frames, int level) {
    Run best;
    for (int repeat = 0; repeat < 3; ++repeat) {
        const Run r = measureOnce(frames, level);
        if (repeat == 0 || r.addMs < best.addMs) best.addMs = r.addMs;
        if (repeat == 0 || r.getMs < best.getMs) best.getMs = r.getMs;
        best.bytesPerFrame = r.bytesPerFrame;
    }
    return best;
}

}  // namespace

int main(int argc, char** argv) try {
    size_t frameCount = 20;
    std::vector<int> levels = {1, 3, 9};
    std::vector<fs::path> folders;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--frames" && i + 1 < argc) {
            frameCount = std::stoul(argv[++i]);
        } else if (a == "--levels" && i + 1 < argc) {
            levels.clear();
            std::istringstream s(argv[++i]);
            for (std::string l; std::getline(s, l, ',');) levels.push_back(std::stoi(l));
        } else {
            folders.emplace_back(a);
        }
    }
    if (folders.empty()) {
        std::fprintf(stderr, "usage: frame_store_bytes [--frames N] [--levels 1,3,9] DATASET_FOLDER...\n");
        return 2;
    }
    for (const fs::path& folder : folders) {
        const auto depthList = listFile(folder / "depth.txt", frameCount);
        const auto rgbList = listFile(folder / "rgb.txt", frameCount);
        std::vector<StoredFrame> depthOnly, withColor;
        size_t pngBytes = 0;
        for (size_t i = 0; i < depthList.size(); ++i) {
            StoredFrame f;
            f.index = uint32_t(i);
            f.timestamp = depthList[i].first;
            f.depth = readDepth(folder / depthList[i].second, 5000.0);
            f.intrinsics = {500, 500, 319.5f, 239.5f, f.depth.width, f.depth.height};
            pngBytes += fs::file_size(folder / depthList[i].second);
            depthOnly.push_back(f);
            f.color = readColor(folder / rgbList.at(i).second);
            withColor.push_back(f);
        }
        const double n = double(depthOnly.size());
        const double pixels = double(depthOnly.at(0).depth.meters.size());
        std::printf("%s: %zu frames of %dx%d; raw depth %.0f B (float), colour %.0f B (RGB8); depth PNG files %.0f B a frame\n",
                    folder.filename().c_str(), depthOnly.size(), depthOnly[0].depth.width, depthOnly[0].depth.height, 4 * pixels,
                    3 * pixels, double(pngBytes) / n);
        std::printf("  level | depth B/frame (%% raw) | colour B/frame (%% raw) | depth add/get ms | colour add/get ms\n");
        for (int level : levels) {
            const Run d = measure(depthOnly, level), dc = measure(withColor, level);
            const double colourBytes = dc.bytesPerFrame - d.bytesPerFrame;
            std::printf("  %5d | %9.0f (%5.1f %%)     | %9.0f (%5.1f %%)      | %6.2f / %6.2f  | %6.2f / %6.2f\n", level, d.bytesPerFrame,
                        100 * d.bytesPerFrame / (4 * pixels), colourBytes, 100 * colourBytes / (3 * pixels), d.addMs, d.getMs,
                        dc.addMs - d.addMs, dc.getMs - d.getMs);
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "frame_store_bytes: %s\n", e.what());
    return 1;
}
