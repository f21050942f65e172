// Place recognition on real pairs (issue 54, step 4): can random ferns tell a view seen again from a few cm and
// 10-20 degrees away from a view of another place, at Kinect quality? And does registering a frame to a keyframe
// that the trajectory's estimate puts nearby verify, with the loop closer's gates, when that estimate has drifted?
//
// For every frame of each dataset (its ground truth poses; frames at least --gap apart only):
//   - the random-fern code of the frame (slam/random_ferns.h, the loop closer's options), and for every pair its
//     dissimilarity, by class of the pair's true relative pose: "same view" pairs within 10 cm whose rotation is
//     in 0-10, 10-20 or 20-30 degrees, and "other place" pairs (optical axes more than 45 degrees apart or cameras
//     more than 1 m apart: little of the one view is in the other; a camera rolled about its axis sees the same place). Printed: each class's percentiles, then for each threshold
//     the share of each class at or below it (a loop candidate).
//   - registration (slam/frame_registration.h, the loop closer's tracker options and width) of up to --icp pairs
//     of each "same view" class, the frame registered to the other from its true pose moved by --drift-cm and
//     --drift-deg (a trajectory that drifted): the share verified by the loop closer's gates (the tracker's loss
//     checks, inliers >= 50 % of the frame, RMSE <= 1.5 cm) and the verified ones' error against the truth.
//
// Not part of the CMake build: linked against the build tree's static libraries. From the checkout, after
// `cmake --build build`:
//   g++ -std=c++20 -O2 -Isrc -Ishaders_comp -Ibuild -isystem /usr/include/eigen3 bench/place_pairs.cpp
//       build/libvkmesh_slam.a build/libvkmesh_io.a build/libvkmesh.a build/libvkmesh_shaders.a build/libvkmesh_base.a
//       -lceres -lglog -lzstd -lvulkan -lopencv_imgcodecs -lopencv_imgproc -lopencv_core -o /tmp/place_pairs
//   /tmp/place_pairs [--gap 30] [--icp 60] [--drift-cm 5] [--drift-deg 2] ../shared/datasets/tum_fr1_rpy ...
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/icp_solve.h"
#include "gpu/tracking/pose_tracker.h"
#include "io/dataset.h"
#include "slam/frame_registration.h"
#include "slam/loop_closer.h"
#include "slam/random_ferns.h"

using namespace vkmesh;

namespace {

struct PairClass {
    const char* name;
    std::vector<double> dissimilarity;
    std::vector<std::pair<size_t, size_t>> pairs;
};

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

Pose perturbed(const Pose& pose, double metres, double degrees, size_t salt) {
    // A fixed, pair-dependent direction (deterministic): translation along one unit vector, rotation about another.
    const double a = 0.7 * double(salt % 97), b = 1.3 * double(salt % 89);
    const Eigen::Vector3d t(std::cos(a), std::sin(a) * std::cos(b), std::sin(a) * std::sin(b));
    const Eigen::Vector3d axis = Eigen::Vector3d(std::sin(b), std::cos(a + b), std::cos(b)).normalized();
    Pose move = Pose::Identity();
    move.block<3, 3>(0, 0) = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis).toRotationMatrix();
    move.block<3, 1>(0, 3) = metres * t;
    return pose * move;
}

}  // namespace

int main(int argc, char** argv) {
    int gap = 30, icpPairs = 60;
    double driftCm = 5, driftDeg = 2;
    std::vector<std::string> folders;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--gap" && i + 1 < argc) gap = std::stoi(argv[++i]);
        else if (a == "--icp" && i + 1 < argc) icpPairs = std::stoi(argv[++i]);
        else if (a == "--drift-cm" && i + 1 < argc) driftCm = std::stod(argv[++i]);
        else if (a == "--drift-deg" && i + 1 < argc) driftDeg = std::stod(argv[++i]);
        else folders.push_back(a);
    }
    const slam::LoopClosureOptions loops;
    const slam::RandomFerns ferns(loops.ferns);
    for (const std::string& folder : folders) {
        const auto dataset = Dataset::open(folder);
        const size_t n = dataset->size();
        std::vector<slam::FernCode> codes(n);
        std::vector<DepthImage> depths(n);
        for (size_t i = 0; i < n; ++i) {
            depths[i] = dataset->loadDepth(i);
            const ColorImage color = dataset->loadColor(i, nullptr, &depths[i]);
            codes[i] = ferns.encode(ferns.shrink(depths[i], color.empty() ? nullptr : &color));
        }
        PairClass classes[4] = {{"same view, 0-10 deg", {}, {}}, {"same view, 10-20 deg", {}, {}}, {"same view, 20-30 deg", {}, {}},
                                {"other place", {}, {}}};
        for (size_t i = 0; i < n; ++i)
            for (size_t j = i + size_t(gap); j < n; ++j) {
                const Pose relative = inverseRigid(dataset->frame(i).cameraToWorld) * dataset->frame(j).cameraToWorld;
                const double metres = translationMetres(relative), degrees = rotationDegrees(relative);
                // Optical axes apart: a camera rolled about its axis still sees the same place.
                const Pose& a = dataset->frame(i).cameraToWorld;
                const Pose& b = dataset->frame(j).cameraToWorld;
                const double axisDegrees = std::acos(std::clamp(a.block<3, 1>(0, 2).dot(b.block<3, 1>(0, 2)), -1.0, 1.0)) * 180.0 / M_PI;
                int c = -1;
                if (metres <= 0.10 && degrees < 30) c = int(degrees / 10);
                else if (axisDegrees > 45 || metres > 1.0) c = 3;
                if (c < 0) continue;
                classes[c].dissimilarity.push_back(slam::RandomFerns::dissimilarity(codes[i], codes[j]));
                classes[c].pairs.emplace_back(i, j);
            }
        std::printf("%s: %zu frames, pairs at least %d frames apart\n", folder.c_str(), n, gap);
        std::printf("  %-22s %8s %6s %6s %6s %6s %6s\n", "fern dissimilarity", "pairs", "p5", "p25", "p50", "p75", "p95");
        for (const PairClass& c : classes)
            std::printf("  %-22s %8zu %6.2f %6.2f %6.2f %6.2f %6.2f\n", c.name, c.dissimilarity.size(), percentile(c.dissimilarity, 0.05),
                        percentile(c.dissimilarity, 0.25), percentile(c.dissimilarity, 0.5), percentile(c.dissimilarity, 0.75),
                        percentile(c.dissimilarity, 0.95));
        std::printf("  share at or below the threshold:\n  %-10s", "threshold");
        for (const PairClass& c : classes) std::printf(" %22s", c.name);
        std::printf("\n");
        for (double threshold : {0.2, 0.3, 0.4, 0.5, 0.6, 0.7}) {
            std::printf("  %-10.2f", threshold);
            for (const PairClass& c : classes) {
                const double share = c.dissimilarity.empty() ? NAN
                                                             : double(std::count_if(c.dissimilarity.begin(), c.dissimilarity.end(),
                                                                                    [&](double d) { return d <= threshold; })) /
                                                                   double(c.dissimilarity.size());
                std::printf(" %21.1f%%", 100 * share);
            }
            std::printf("\n");
        }

        // Registration from a drifted estimate, with the loop closer's gates.
        std::printf("  registration from the true pose moved %.1f cm, %.1f deg (the loop closer's gates):\n", driftCm, driftDeg);
        for (int c = 0; c < 3; ++c) {
            const auto& pairs = classes[c].pairs;
            const size_t tries = std::min(pairs.size(), size_t(icpPairs));
            int verified = 0;
            std::vector<double> errorsCm, errorsDeg;
            for (size_t k = 0; k < tries; ++k) {
                const auto [i, j] = pairs[k * pairs.size() / tries];   // spread over the class
                const Intrinsics& K = dataset->intrinsics();
                const auto frame = slam::registrationFrame(depths[j], K, loops.tracker, loops.registrationWidth);
                const auto key = slam::registrationFrame(depths[i], K, loops.tracker, loops.registrationWidth);
                const Pose truth = dataset->frame(j).cameraToWorld;
                const Pose initial = perturbed(truth, driftCm / 100, driftDeg, k);
                const slam::Registration r = slam::registerFrame(frame, key, dataset->frame(i).cameraToWorld, initial, loops.tracker);
                gpu::TrackerOptions checks = loops.tracker;
                checks.maxJumpMetres = checks.maxJumpDegrees = 1e9;
                const uint32_t verdict = gpu::trackingLoss(r.system, r.solved, r.conditioning, inverseRigid(initial) * r.cameraToWorld, {}, checks);
                if (verdict != gpu::TRACK_TRACKED || r.inlierShare() < loops.minInlierShare || r.system.rmse() > loops.maxRmse) continue;
                ++verified;
                const Pose error = inverseRigid(truth) * r.cameraToWorld;
                errorsCm.push_back(100 * translationMetres(error));
                errorsDeg.push_back(rotationDegrees(error));
            }
            std::printf("  %-22s %3d of %3zu verified; error median %.2f cm %.2f deg, p90 %.2f cm %.2f deg\n", classes[c].name, verified, tries,
                        percentile(errorsCm, 0.5), percentile(errorsDeg, 0.5), percentile(errorsCm, 0.9), percentile(errorsDeg, 0.9));
        }
    }
}
