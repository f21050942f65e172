// Place recognition by random ferns (Glocker et al., ISMAR 2013 / TVCG 2015; ElasticFusion and InfiniTAM relocalise
// with them; ../shared/docs/global-consistency.md): a frame is shrunk to a tiny RGB-D image, and each fern reads one
// pixel of it and compares its red, green, blue and depth with four random thresholds: a 4-bit code. A frame's
// code is its ferns' outputs; two frames' dissimilarity is the share of ferns whose codes differ. No training, no
// descriptor matching, and a cost per frame bounded by the image size and the fern count.
//
// The ferns are drawn from a fixed seed with the generator's raw output (std::mt19937 is specified bit for bit;
// the standard distributions are not): the same frames give the same codes on every platform.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace vkmesh::slam {

struct FernOptions {
    int ferns = 500;             // ElasticFusion's count
    int width = 80, height = 60; // the tiny image (the frame's pixels averaged in blocks)
    float minDepth = 0.4f;       // depth thresholds are drawn in [minDepth, maxDepth] metres
    float maxDepth = 4.0f;
    uint32_t seed = 1;
    // The tiny image is blurred (a 5-tap binomial filter, this many times), so that a code changes little for a
    // view a few pixels away (InfiniTAM blurs its 40 x 30 image with sigma 2.5): a room's textures and edges
    // otherwise flip a third of the ferns for a 2 cm, 1 degree move.
    int blurPasses = 2;
    // Whether frames of this size can be shrunk to the tiny image (RandomFerns::shrink refuses smaller ones).
    bool fits(int frameWidth, int frameHeight) const { return frameWidth >= width && frameHeight >= height; }
};

// The tiny image a code is computed from (also what a keyframe keeps to be recognised by).
struct FernImage {
    int width = 0, height = 0;
    std::vector<float> depth;     // metres, block mean of the measured samples, 0 = none
    std::vector<uint8_t> rgb;     // block mean, 3 per pixel; empty without colour
};

using FernCode = std::vector<uint8_t>;   // one 4-bit value per fern

class RandomFerns {
public:
    explicit RandomFerns(const FernOptions& options = {});
    // The frame shrunk to options' size: each tiny pixel averages its block of the frame (depth: the measured
    // samples only; colour, when given and not empty, registered to the depth). Throws Error for an image
    // smaller than the tiny one or sizes that disagree.
    FernImage shrink(const DepthImage& depth, const ColorImage* color) const;
    FernCode encode(const FernImage& image) const;
    // The share of ferns whose codes differ, in [0, 1] (1 for codes of different lengths).
    static double dissimilarity(const FernCode& a, const FernCode& b);
    const FernOptions& options() const { return options_; }

private:
    static void blur(FernImage& image);
    struct Fern {
        int pixel = 0;                 // in the tiny image
        uint8_t red = 0, green = 0, blue = 0;
        float depth = 0;
    };
    FernOptions options_;
    std::vector<Fern> ferns_;
};

}  // namespace vkmesh::slam
