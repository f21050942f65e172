#include "slam/session_registration.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>

#include "core/camera.h"
#include "core/icp_solve.h"

namespace vkmesh::slam {

namespace {

using Clock = std::chrono::steady_clock;

bool agree(const Pose& a, const Pose& b, const SessionRegistrationOptions& o) {
    const Pose d = inverseRigid(a) * b;
    return translationMetres(d) <= o.agreeMetres && rotationDegrees(d) <= o.agreeDegrees;
}

// The mean of rigid transforms close to each other: translations averaged, rotations as the normalised mean of
// their quaternions (signs aligned with the first), which is the rotation mean to first order for small spreads.
Pose meanTransform(const std::vector<Pose>& transforms) {
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    Eigen::Vector4d q = Eigen::Vector4d::Zero();
    const Eigen::Quaterniond first(Eigen::Matrix3d(transforms.front().block<3, 3>(0, 0)));
    for (const Pose& p : transforms) {
        t += p.block<3, 1>(0, 3);
        Eigen::Quaterniond r(Eigen::Matrix3d(p.block<3, 3>(0, 0)));
        if (r.dot(first) < 0) r.coeffs() = -r.coeffs();
        q += r.coeffs();
    }
    Pose mean = Pose::Identity();
    mean.block<3, 3>(0, 0) = Eigen::Quaterniond(q.normalized()).toRotationMatrix();
    mean.block<3, 1>(0, 3) = t / double(transforms.size());
    return mean;
}

struct Keyframe {
    uint32_t frame = 0;
    Pose pose = Pose::Identity();
    FernCode code;
};

std::vector<Keyframe> keyframesOf(const FrameStore& store, const std::vector<uint32_t>& frames, const RandomFerns& ferns) {
    std::vector<Keyframe> out;
    for (uint32_t index : frames) {
        const StoredFrame f = store.get(index);
        out.push_back({index, f.pose, ferns.encode(ferns.shrink(f.depth, f.color.empty() ? nullptr : &f.color))});
    }
    return out;
}

}  // namespace

std::vector<uint32_t> storedKeyframes(const FrameStore& store, double keyframeMetres, double keyframeDegrees) {
    std::vector<uint32_t> out;
    for (uint32_t index : store.indices()) {
        if (!out.empty()) {
            const Pose motion = inverseRigid(store.pose(out.back())) * store.pose(index);
            if (translationMetres(motion) < keyframeMetres && rotationDegrees(motion) < keyframeDegrees) continue;
        }
        out.push_back(index);
    }
    return out;
}

SessionRegistration registerSessions(const FrameStore& first, const FrameStore& second, const SessionRegistrationOptions& options) {
    const auto start = Clock::now();
    if (first.size() == 0) throw Error("registering two sessions: the first map's frame store holds no frame");
    if (second.size() == 0) throw Error("registering two sessions: the second map's frame store holds no frame");
    SessionRegistration out;
    const RandomFerns ferns(options.ferns);

    const std::vector<Keyframe> firstKeys = keyframesOf(first, storedKeyframes(first, options.keyframeMetres, options.keyframeDegrees), ferns);
    std::vector<uint32_t> secondFrames = storedKeyframes(second, options.keyframeMetres, options.keyframeDegrees);
    out.firstKeyframes = firstKeys.size();
    out.secondKeyframes = secondFrames.size();
    if (int(secondFrames.size()) > options.maxSecondKeyframes) {   // spread evenly over the session
        std::vector<uint32_t> spread;
        for (int i = 0; i < options.maxSecondKeyframes; ++i)
            spread.push_back(secondFrames[size_t(i) * secondFrames.size() / size_t(options.maxSecondKeyframes)]);
        secondFrames = spread;
    }
    const std::vector<Keyframe> secondKeys = keyframesOf(second, secondFrames, ferns);
    out.secondKeyframesTried = secondKeys.size();

    // Registration pyramids are made once per keyframe, when a pair first needs one.
    std::map<uint32_t, RegistrationFrame> firstPyramids;
    auto pyramidOf = [&](const FrameStore& store, uint32_t index) {
        const StoredFrame f = store.get(index);
        return registrationFrame(f.depth, f.intrinsics, options.tracker, options.registrationWidth);
    };
    for (const Keyframe& s : secondKeys) {
        std::vector<std::pair<double, size_t>> ranked;
        for (size_t k = 0; k < firstKeys.size(); ++k) {
            const double d = RandomFerns::dissimilarity(s.code, firstKeys[k].code);
            if (d <= options.maxDissimilarity) ranked.emplace_back(d, k);
        }
        std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        if (ranked.size() > size_t(options.candidates)) ranked.resize(size_t(options.candidates));
        if (ranked.empty()) continue;
        const RegistrationFrame frame = pyramidOf(second, s.frame);
        for (const auto& [dissimilarity, k] : ranked) {
            const Keyframe& f = firstKeys[k];
            auto it = firstPyramids.find(f.frame);
            if (it == firstPyramids.end()) it = firstPyramids.emplace(f.frame, pyramidOf(first, f.frame)).first;
            SessionMatch m;
            m.secondFrame = s.frame;
            m.firstFrame = f.frame;
            m.dissimilarity = dissimilarity;
            ++out.registrations;
            try {
                const VerifiedRegistration v = verifyRegistration(frame, it->second, f.pose, {f.pose}, options.tracker, options.gates);
                m.verified = v.match.has_value();
                m.failure = v.failure;
                if (v.match) {
                    m.secondToFirst = v.match->cameraToWorld * inverseRigid(s.pose);
                    m.rmse = v.match->system.rmse();
                }
            } catch (const Error& e) {   // e.g. frames whose pyramids differ in size: this pair cannot be compared
                m.failure = e.what();
            }
            out.verified += m.verified;
            out.matches.push_back(m);
        }
    }

    // The transform most verified pairs agree on.
    std::vector<size_t> verified;
    for (size_t i = 0; i < out.matches.size(); ++i)
        if (out.matches[i].verified) verified.push_back(i);
    auto agreeingWith = [&](size_t i, const std::vector<size_t>& among) {
        std::vector<size_t> set;
        for (size_t j : among)
            if (agree(out.matches[i].secondToFirst, out.matches[j].secondToFirst, options)) set.push_back(j);
        return set;
    };
    std::vector<size_t> best;
    for (size_t i : verified) {
        const std::vector<size_t> set = agreeingWith(i, verified);
        if (set.size() > best.size()) best = set;
    }
    auto summary = [&] {
        std::map<std::string, int> reasons;
        for (const SessionMatch& m : out.matches)
            if (!m.verified) {   // the reason without its numbers: "inliers cover", "too few inliers", ...
                std::string reason = m.failure.substr(0, m.failure.find_first_of(":(0123456789"));
                while (!reason.empty() && reason.back() == ' ') reason.pop_back();
                ++reasons[reason];
            }
        std::string text = std::to_string(out.secondKeyframesTried) + " of the second session's keyframes against the first's " +
                           std::to_string(out.firstKeyframes) + ": " + std::to_string(out.registrations) + " pairs registered, " +
                           std::to_string(out.verified) + " verified";
        for (const auto& [reason, count] : reasons) text += "; " + std::to_string(count) + " rejected: " + reason;
        return text;
    };
    if (int(best.size()) < options.minAgreeing)
        throw Error("the two sessions could not be registered: " + std::to_string(best.size()) + " verified pairs agree on a transform, " +
                    std::to_string(options.minAgreeing) + " needed (" + summary() +
                    "). Do the maps see a common part of the place, with the same camera and settings?");
    // The other verified pairs, but those next to the agreeing ones (a registration's noise spreads the transforms;
    // neighbours of the set are not a second place).
    std::vector<size_t> rest;
    for (size_t i : verified) {
        bool near = false;
        for (size_t j : best) near = near || agree(out.matches[i].secondToFirst, out.matches[j].secondToFirst, options);
        if (!near) rest.push_back(i);
    }
    for (size_t i : rest) {
        const std::vector<size_t> other = agreeingWith(i, rest);
        if (int(other.size()) >= options.minAgreeing)
            throw Error("the two sessions could not be registered: the place is ambiguous, " + std::to_string(best.size()) + " pairs agree on one transform and " +
                        std::to_string(other.size()) + " on another " +
                        std::to_string(translationMetres(inverseRigid(out.matches[best.front()].secondToFirst) * out.matches[i].secondToFirst)) +
                        " m away (" + summary() + ")");
    }
    std::vector<Pose> transforms;
    for (size_t i : best) transforms.push_back(out.matches[i].secondToFirst), out.matches[i].agrees = true;
    out.secondToFirst = meanTransform(transforms);
    out.agreeing = best.size();
    for (const Pose& t : transforms) {
        const Pose d = inverseRigid(out.secondToFirst) * t;
        out.spreadMetres = std::max(out.spreadMetres, translationMetres(d));
        out.spreadDegrees = std::max(out.spreadDegrees, rotationDegrees(d));
    }
    out.milliseconds = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return out;
}

}  // namespace vkmesh::slam
