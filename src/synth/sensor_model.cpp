// The synthetic sensor: depth rendering by sphere tracing, the Kinect-like depth noise and dropout, colour
// rendering (exposure, noise), the Kinect intrinsics, and the per-pixel / per-frame random streams.
#include "synth/synthetic_scene.h"
#include "synth/synthetic_scene_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace vkmesh::synth {

using detail::degrees;
using detail::intersectRay;
using detail::kPi;

namespace {

constexpr int kRenderThreads = 2;  // the development and CI machines have two cores

// Kinect v1 noise model (Nguyen, Izadi, Lovell: "Modeling Kinect sensor noise for improved 3D
// reconstruction and tracking", 3DIMPVT 2012), and dropout where structured light loses its pattern.
double axialNoiseSigma(double depth) { return 0.0012 + 0.0019 * (depth - 0.4) * (depth - 0.4); }
constexpr double kGrazingDropStartDegrees = 70.0;
constexpr double kGrazingDropAlwaysDegrees = 80.0;
constexpr double kGrazingDropProbabilityAtAlways = 0.5;
constexpr double kEdgeDropProbability = 0.5;
constexpr double kDiscontinuityRelativeJump = 0.04;

// SplitMix64: a tiny counter-based generator, seeded per pixel so the noise does not depend on how the rows
// are split between threads.
class PixelRandom {
public:
    PixelRandom(uint32_t seed, uint64_t pixel) : state_((static_cast<uint64_t>(seed) << 32) ^ pixel) {}
    uint64_t next() {
        uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
    double gaussian() {                                                           // Box-Muller
        const double u1 = 1.0 - uniform();                                       // (0, 1]: log is finite
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
    }

private:
    uint64_t state_;
};

Rgb shade(const Rgb& c, double exposure, double noiseSigma, PixelRandom* random) {
    Rgb out;
    for (int k = 0; k < 3; ++k) {
        double v = c[k] * exposure;
        if (random) v += noiseSigma * random->gaussian();
        out[k] = static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
    }
    return out;
}

void validatePoseForRendering(const Pose& cameraToWorld) {
    const Eigen::Matrix3d rotation = cameraToWorld.topLeftCorner<3, 3>();
    const double orthonormalError = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!cameraToWorld.allFinite() || orthonormalError > 1e-6 || rotation.determinant() < 0 ||
        (cameraToWorld.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12) {
        std::ostringstream out;
        out << "renderDepth: cameraToWorld is not a rigid transform:\n" << cameraToWorld;
        throw Error(out.str());
    }
}

// Applies the Kinect-like sensor model to a clean depth image. cosIncidence[i] is |normal . ray| at pixel i.
void applySensorNoise(DepthImage& depth, const std::vector<double>& cosIncidence, uint32_t seed) {
    const DepthImage clean = depth;
    const double cosAlwaysDrop = std::cos(degrees(kGrazingDropAlwaysDegrees));
    auto isDiscontinuity = [&](int x, int y, double z) {
        const std::array<std::array<int, 2>, 4> neighbours{{{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}}};
        for (const auto& [nx, ny] : neighbours) {
            if (nx < 0 || ny < 0 || nx >= clean.width || ny >= clean.height) continue;
            const double neighbourDepth = clean.at(nx, ny);
            if (neighbourDepth <= 0 || std::abs(neighbourDepth - z) > kDiscontinuityRelativeJump * z) return true;
        }
        return false;
    };
    for (int y = 0; y < depth.height; ++y) {
        for (int x = 0; x < depth.width; ++x) {
            const size_t index = static_cast<size_t>(y) * depth.width + x;
            const double z = clean.meters[index];
            if (z <= 0) continue;
            // Always draw the same three numbers per pixel, so one pixel's fate never shifts another's.
            PixelRandom random(seed, index);
            const double grazingDraw = random.uniform();
            const double edgeDraw = random.uniform();
            const double gaussian = random.gaussian();

            const double incidenceDegrees = std::acos(std::clamp(cosIncidence[index], 0.0, 1.0)) * 180.0 / kPi;
            double grazingDropProbability = 0;
            if (cosIncidence[index] < cosAlwaysDrop)
                grazingDropProbability = 1;
            else if (incidenceDegrees > kGrazingDropStartDegrees)
                grazingDropProbability = kGrazingDropProbabilityAtAlways * (incidenceDegrees - kGrazingDropStartDegrees) /
                                         (kGrazingDropAlwaysDegrees - kGrazingDropStartDegrees);
            const bool dropped = grazingDraw < grazingDropProbability ||
                                 (isDiscontinuity(x, y, z) && edgeDraw < kEdgeDropProbability);
            const double noisy = z + axialNoiseSigma(z) * gaussian;
            depth.meters[index] = dropped || noisy <= 0 ? 0.0f : static_cast<float>(noisy);
        }
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
uint32_t frameSeed(uint32_t seed, size_t frame) {
    PixelRandom mixer(seed, 0xF4A3E5000000ull + frame);
    return static_cast<uint32_t>(mixer.next() >> 32);
}

Intrinsics kinectIntrinsics(int width, int height) {
    if (width <= 0 || height <= 0)
        throw Error("kinectIntrinsics: image size " + std::to_string(width) + "x" + std::to_string(height) +
                    " must be positive");
    Intrinsics intrinsics;
    intrinsics.fx = static_cast<float>(525.0 * width / 640.0);
    intrinsics.fy = static_cast<float>(525.0 * height / 480.0);
    // Scale about the image corner in continuous coordinates (pixel centres at integers: corner at -0.5).
    intrinsics.cx = static_cast<float>((319.5 + 0.5) * width / 640.0 - 0.5);
    intrinsics.cy = static_cast<float>((239.5 + 0.5) * height / 480.0 - 0.5);
    intrinsics.width = width;
    intrinsics.height = height;
    return intrinsics;
}

void validateIntrinsics(const Intrinsics& intrinsics) {
    auto fail = [](const std::string& what) { throw Error("bad intrinsics: " + what); };
    if (intrinsics.width <= 0 || intrinsics.height <= 0)
        fail("image size " + std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height) +
             " must be positive");
    if (!std::isfinite(intrinsics.fx) || intrinsics.fx == 0) fail("fx = " + std::to_string(intrinsics.fx) + " must be finite and non-zero");
    if (!std::isfinite(intrinsics.fy) || intrinsics.fy == 0) fail("fy = " + std::to_string(intrinsics.fy) + " must be finite and non-zero");
    if (!std::isfinite(intrinsics.cx)) fail("cx = " + std::to_string(intrinsics.cx) + " must be finite");
    if (!std::isfinite(intrinsics.cy)) fail("cy = " + std::to_string(intrinsics.cy) + " must be finite");
}

DepthImage SyntheticScene::renderDepth(const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                       const RenderOptions& options, ColorImage* color) const {
    validateIntrinsics(intrinsics);
    validatePoseForRendering(cameraToWorld);
    if (!std::isfinite(options.maxRange) || options.maxRange <= 0)
        throw Error("renderDepth: maxRange = " + std::to_string(options.maxRange) + " must be positive and finite");
    if (!std::isfinite(options.exposure) || options.exposure < 0 || !std::isfinite(options.colorNoise) || options.colorNoise < 0)
        throw Error("renderDepth: exposure = " + std::to_string(options.exposure) + " and colorNoise = " +
                    std::to_string(options.colorNoise) + " must be finite and >= 0");
    if (color) {
        color->width = intrinsics.width;
        color->height = intrinsics.height;
        color->rgb.assign(static_cast<size_t>(intrinsics.width) * intrinsics.height * 3, 0);
    }

    DepthImage depth;
    depth.width = intrinsics.width;
    depth.height = intrinsics.height;
    const size_t pixelCount = static_cast<size_t>(depth.width) * depth.height;
    depth.meters.assign(pixelCount, 0.0f);
    std::vector<double> cosIncidence(options.noise ? pixelCount : 0, 1.0);

    const Eigen::Matrix3d rotation = cameraToWorld.topLeftCorner<3, 3>();
    const Eigen::Vector3d origin = cameraToWorld.topRightCorner<3, 1>();
    auto renderRows = [&](int firstRow) {
        for (int v = firstRow; v < depth.height; v += kRenderThreads) {
            for (int u = 0; u < depth.width; ++u) {
                const Eigen::Vector3d cameraRay((u - intrinsics.cx) / intrinsics.fx, (v - intrinsics.cy) / intrinsics.fy, 1.0);
                const double rayLengthPerDepth = cameraRay.norm();  // the ray's z component is 1
                const Eigen::Vector3d direction = rotation * (cameraRay / rayLengthPerDepth);
                const std::optional<double> hit =
                    intersectRay(*this, origin, direction, options.maxRange * rayLengthPerDepth);
                if (!hit) continue;
                const size_t index = static_cast<size_t>(v) * depth.width + u;
                depth.meters[index] = static_cast<float>(*hit / rayLengthPerDepth);
                if (options.noise) cosIncidence[index] = std::abs(normal(origin + *hit * direction).dot(direction));
                if (color) {
                    // Its own random stream (seed mixed with a constant), so colour noise leaves depth noise as it was.
                    PixelRandom random(options.seed ^ 0xC0102u, index);
                    const Rgb c = shade(this->color(origin + *hit * direction), options.exposure, options.colorNoise,
                                        options.colorNoise > 0 ? &random : nullptr);
                    std::copy(c.begin(), c.end(), color->rgb.begin() + static_cast<std::ptrdiff_t>(index * 3));
                }
            }
        }
    };
    std::vector<std::thread> workers;
    for (int thread = 1; thread < kRenderThreads; ++thread) workers.emplace_back(renderRows, thread);
    renderRows(0);
    for (std::thread& worker : workers) worker.join();

    if (options.noise) applySensorNoise(depth, cosIncidence, options.seed);
    return depth;
}

}  // namespace vkmesh::synth
