#include "slam/random_ferns.h"

#include <cmath>
#include <random>
#include <string>

namespace vkmesh::slam {

RandomFerns::RandomFerns(const FernOptions& options) : options_(options) {
    if (options.ferns < 1 || options.width < 1 || options.height < 1 || !(options.minDepth > 0) || !(options.maxDepth > options.minDepth))
        throw Error("random ferns: need at least one fern, a tiny image of at least 1x1 and 0 < minDepth < maxDepth");
    std::mt19937 random(options.seed);
    // Raw 32-bit outputs mapped by hand: std::uniform_*_distribution differ between standard libraries.
    auto uniform = [&random] { return double(random()) / 4294967296.0; };   // [0, 1)
    const int pixels = options.width * options.height;
    ferns_.resize(size_t(options.ferns));
    for (Fern& f : ferns_) {
        f.pixel = int(uniform() * pixels);
        f.red = uint8_t(uniform() * 256);
        f.green = uint8_t(uniform() * 256);
        f.blue = uint8_t(uniform() * 256);
        f.depth = float(options.minDepth + uniform() * (options.maxDepth - options.minDepth));
    }
}

FernImage RandomFerns::shrink(const DepthImage& depth, const ColorImage* color) const {
    const int w = options_.width, h = options_.height;
    if (!options_.fits(depth.width, depth.height) || depth.meters.size() != size_t(depth.width) * size_t(depth.height))
        throw Error("random ferns: a " + std::to_string(depth.width) + "x" + std::to_string(depth.height) + " depth image cannot shrink to " +
                    std::to_string(w) + "x" + std::to_string(h));
    const bool withColor = color && !color->empty();
    if (withColor && (color->width != depth.width || color->height != depth.height ||
                      color->rgb.size() != size_t(color->width) * size_t(color->height) * 3))
        throw Error("random ferns: the colour image is not registered to the " + std::to_string(depth.width) + "x" +
                    std::to_string(depth.height) + " depth image");
    FernImage out;
    out.width = w;
    out.height = h;
    out.depth.assign(size_t(w) * h, 0.0f);
    if (withColor) out.rgb.assign(size_t(w) * h * 3, 0);
    for (int ty = 0; ty < h; ++ty) {
        const int y0 = ty * depth.height / h, y1 = (ty + 1) * depth.height / h;
        for (int tx = 0; tx < w; ++tx) {
            const int x0 = tx * depth.width / w, x1 = (tx + 1) * depth.width / w;
            double depthSum = 0;
            int measured = 0;
            uint64_t rgbSum[3] = {0, 0, 0};
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const size_t i = size_t(y) * depth.width + x;
                    const float d = depth.meters[i];
                    if (std::isfinite(d) && d > 0) depthSum += d, ++measured;
                    if (withColor)
                        for (int c = 0; c < 3; ++c) rgbSum[c] += color->rgb[i * 3 + c];
                }
            const size_t t = size_t(ty) * w + tx;
            out.depth[t] = measured > 0 ? float(depthSum / measured) : 0.0f;
            const uint64_t n = uint64_t(x1 - x0) * uint64_t(y1 - y0);
            if (withColor)
                for (int c = 0; c < 3; ++c) out.rgb[t * 3 + c] = uint8_t((rgbSum[c] + n / 2) / n);
        }
    }
    for (int pass = 0; pass < options_.blurPasses; ++pass) blur(out);
    return out;
}

void RandomFerns::blur(FernImage& image) {
    // A 5-tap binomial filter (1 4 6 4 1) / 16 along x, then y; depth averages the measured samples only and
    // stays 0 where none is near. Integer arithmetic for the colour: the same codes on every compiler.
    const int w = image.width, h = image.height;
    const int taps[5] = {1, 4, 6, 4, 1};
    const bool withColor = !image.rgb.empty();
    for (int axis = 0; axis < 2; ++axis) {
        std::vector<float> depth(image.depth.size(), 0.0f);
        std::vector<uint8_t> rgb(image.rgb.size(), 0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                float depthSum = 0, depthWeight = 0;
                int rgbSum[3] = {0, 0, 0}, rgbWeight = 0;
                for (int k = -2; k <= 2; ++k) {
                    const int sx = axis == 0 ? x + k : x, sy = axis == 1 ? y + k : y;
                    if (sx < 0 || sy < 0 || sx >= w || sy >= h) continue;
                    const size_t s = size_t(sy) * w + sx;
                    const int weight = taps[k + 2];
                    if (image.depth[s] > 0) depthSum += float(weight) * image.depth[s], depthWeight += float(weight);
                    if (withColor) {
                        for (int c = 0; c < 3; ++c) rgbSum[c] += weight * image.rgb[s * 3 + c];
                        rgbWeight += weight;
                    }
                }
                const size_t t = size_t(y) * w + x;
                depth[t] = depthWeight > 0 ? depthSum / depthWeight : 0.0f;
                if (withColor)
                    for (int c = 0; c < 3; ++c) rgb[t * 3 + c] = uint8_t((rgbSum[c] + rgbWeight / 2) / rgbWeight);
            }
        image.depth = std::move(depth);
        image.rgb = std::move(rgb);
    }
}

FernCode RandomFerns::encode(const FernImage& image) const {
    if (image.width != options_.width || image.height != options_.height || image.depth.size() != size_t(image.width) * image.height)
        throw Error("random ferns: the image to encode is not the tiny image of these ferns");
    const bool withColor = !image.rgb.empty();
    FernCode code(ferns_.size());
    for (size_t i = 0; i < ferns_.size(); ++i) {
        const Fern& f = ferns_[i];
        uint8_t bits = image.depth[size_t(f.pixel)] > f.depth ? 1 : 0;   // no depth: below every threshold
        if (withColor) {
            const uint8_t* rgb = &image.rgb[size_t(f.pixel) * 3];
            bits |= uint8_t((rgb[0] > f.red) << 1 | (rgb[1] > f.green) << 2 | (rgb[2] > f.blue) << 3);
        }
        code[i] = bits;
    }
    return code;
}

double RandomFerns::dissimilarity(const FernCode& a, const FernCode& b) {
    if (a.size() != b.size() || a.empty()) return 1.0;
    size_t differ = 0;
    for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
    return double(differ) / double(a.size());
}

}  // namespace vkmesh::slam
