#include "slam/feature_relocaliser.h"

#include <algorithm>
#include <cstring>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/types.h"

namespace vkmesh::slam {
namespace {

constexpr int kDescriptorBytes = 32;   // ORB's 256 bits

// The colour image as OpenCV's grey image (a copy: ORB needs one channel).
cv::Mat grey(const ColorImage& color) {
    if (color.width <= 0 || color.height <= 0 || color.rgb.size() != size_t(color.width) * size_t(color.height) * 3)
        throw Error("relocalisation by features: a colour image of " + std::to_string(color.width) + " x " + std::to_string(color.height) +
                    " pixels holds " + std::to_string(color.rgb.size()) + " bytes");
    const cv::Mat rgb(color.height, color.width, CV_8UC3, const_cast<uint8_t*>(color.rgb.data()));
    cv::Mat out;
    cv::cvtColor(rgb, out, cv::COLOR_RGB2GRAY);
    return out;
}

void detect(const FeatureOptions& o, const ColorImage& color, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
    // OpenCV's ORB defaults (8 levels, scale 1.2, FAST threshold 20) but the count.
    cv::Ptr<cv::ORB> orb = cv::ORB::create(o.features);
    orb->detectAndCompute(grey(color), cv::noArray(), keypoints, descriptors);
}

cv::Matx33d cameraMatrix(const Intrinsics& k) { return {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1}; }

}  // namespace

FeatureRelocaliser::FeatureRelocaliser(const FeatureOptions& options) : options_(options) {
    if (options.features < 8 || options.minMatches < 6 || options.minInliers < 6 || options.candidates < 1 || options.solveKeyframes < 1 ||
        options.matchKeyframes < 4 ||
        !(options.ratio > 0 && options.ratio <= 1) || options.maxDistance < 1 || !(options.reprojectionPixels > 0) || options.ransacIterations < 1)
        throw Error("relocalisation by features: at least 8 features, 6 matches and 6 inliers, 1 candidate and 1 keyframe to solve, a ratio in "
                    "(0, 1], 4 keyframes to match, a positive distance bound and reprojection threshold, and at least one RANSAC iteration");
}

KeyframeFeatures FeatureRelocaliser::describe(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics) const {
    KeyframeFeatures out;
    if (!options_.enabled || !color || color->empty()) return out;
    if (color->width != depth.width || color->height != depth.height)
        throw Error("relocalisation by features: the colour image is " + std::to_string(color->width) + " x " + std::to_string(color->height) +
                    ", its depth " + std::to_string(depth.width) + " x " + std::to_string(depth.height));
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    detect(options_, *color, keypoints, descriptors);
    for (size_t i = 0; i < keypoints.size(); ++i) {
        const int x = int(keypoints[i].pt.x + 0.5f), y = int(keypoints[i].pt.y + 0.5f);
        if (x < 0 || y < 0 || x >= depth.width || y >= depth.height) continue;
        const float z = depth.at(x, y);
        if (!(z >= options_.minDepth && z <= options_.maxDepth)) continue;
        out.points.push_back((keypoints[i].pt.x - intrinsics.cx) / intrinsics.fx * z);
        out.points.push_back((keypoints[i].pt.y - intrinsics.cy) / intrinsics.fy * z);
        out.points.push_back(z);
        const uint8_t* row = descriptors.ptr<uint8_t>(int(i));
        out.descriptors.insert(out.descriptors.end(), row, row + kDescriptorBytes);
    }
    return out;
}

std::vector<FeatureCandidate> FeatureRelocaliser::propose(const ColorImage* color, const Intrinsics& intrinsics,
                                                          const std::vector<const KeyframeFeatures*>& keyframes) const {
    std::vector<FeatureCandidate> found;
    if (!options_.enabled || !color || color->empty() || keyframes.empty()) return found;
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    detect(options_, *color, keypoints, descriptors);
    if (int(keypoints.size()) < options_.minMatches) return found;
    const cv::BFMatcher matcher(cv::NORM_HAMMING);
    const cv::Matx33d K = cameraMatrix(intrinsics);
    // Every keyframe's matches (the ratio test, and a distance bound: most ratio-passing matches of a real frame to
    // a keyframe of another place are chance ones), then PnP for the keyframes with the most, which bounds the
    // RANSAC's cost by solveKeyframes whatever the map's size.
    struct Matched {
        size_t keyframe;
        std::vector<cv::Point3f> object;
        std::vector<cv::Point2f> image;
    };
    std::vector<Matched> matched;
    for (size_t k = 0; k < keyframes.size(); ++k) {
        const KeyframeFeatures& kf = *keyframes[k];
        if (int(kf.count()) < options_.minMatches) continue;
        const cv::Mat kfDescriptors(int(kf.count()), kDescriptorBytes, CV_8U, const_cast<uint8_t*>(kf.descriptors.data()));
        std::vector<std::vector<cv::DMatch>> knn;
        matcher.knnMatch(descriptors, kfDescriptors, knn, 2);
        Matched m{k, {}, {}};
        for (const auto& pair : knn) {
            if (pair.size() < 2 || !(pair[0].distance < options_.ratio * pair[1].distance) || pair[0].distance > options_.maxDistance) continue;
            const float* p = &kf.points[size_t(pair[0].trainIdx) * 3];
            m.object.emplace_back(p[0], p[1], p[2]);
            m.image.push_back(keypoints[size_t(pair[0].queryIdx)].pt);
        }
        if (int(m.object.size()) >= options_.minMatches) matched.push_back(std::move(m));
    }
    std::stable_sort(matched.begin(), matched.end(), [](const Matched& a, const Matched& b) { return a.object.size() > b.object.size(); });
    if (matched.size() > size_t(options_.solveKeyframes)) matched.resize(size_t(options_.solveKeyframes));
    for (const Matched& m : matched) {
        const std::vector<cv::Point3f>& object = m.object;
        const std::vector<cv::Point2f>& image = m.image;
        cv::theRNG().state = 0x12345678u + m.keyframe;   // the same frames give the same poses
        cv::Mat rvec, tvec;
        std::vector<int> inliers;
        const bool solved = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, options_.ransacIterations,
                                               float(options_.reprojectionPixels), 0.999, inliers, cv::SOLVEPNP_EPNP);
        if (!solved || int(inliers.size()) < options_.minInliers || double(inliers.size()) < options_.minInlierShare * double(object.size()))
            continue;
        // Refined on the inliers (Levenberg-Marquardt from the RANSAC's pose).
        std::vector<cv::Point3f> objectIn;
        std::vector<cv::Point2f> imageIn;
        for (const int i : inliers) objectIn.push_back(object[size_t(i)]), imageIn.push_back(image[size_t(i)]);
        cv::solvePnPRefineLM(objectIn, imageIn, K, cv::noArray(), rvec, tvec);
        cv::Matx33d R;
        cv::Rodrigues(rvec, R);
        FeatureCandidate c;
        c.keyframe = int(m.keyframe);
        for (int r = 0; r < 3; ++r) {
            for (int col = 0; col < 3; ++col) c.keyframeToCamera(r, col) = R(r, col);
            c.keyframeToCamera(r, 3) = tvec.at<double>(r);
        }
        c.matches = int(object.size());
        c.inliers = int(inliers.size());
        found.push_back(c);
    }
    // Most inliers first; ties: in the order the keyframes were given.
    std::stable_sort(found.begin(), found.end(), [](const FeatureCandidate& a, const FeatureCandidate& b) { return a.inliers > b.inliers; });
    if (found.size() > size_t(options_.candidates)) found.resize(size_t(options_.candidates));
    return found;
}

}  // namespace vkmesh::slam
