#include "slam/loop_closer.h"

#include <zstd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>

#include "core/camera.h"
#include "core/map_format.h"
#include "gpu/tracking/pose_tracker.h"

namespace vkmesh::slam {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;

}  // namespace

LoopCloser::LoopCloser(const LoopClosureOptions& options) : options_(options), ferns_(options.ferns), features_(options.features) {
    gpu::trackParamsFor(options.tracker);   // checked now
    if (options.registrationWidth < 40 || options.candidates < 1 || options.relocaliseCandidates < 1 || !(options.keyframeMetres > 0) ||
        !(options.keyframeDegrees > 0))
        throw Error("loop closure: the registration must be at least 40 pixels wide, candidates at least 1 and the keyframe spacing positive");
}

void LoopCloser::time(const std::string& stage, double ms) {
    auto& [sum, count] = stats_.milliseconds[stage];
    sum += ms;
    ++count;
}

bool LoopCloser::latestPose(uint32_t frame, Pose& pose) const {
    const auto it = frames_.find(frame);
    if (it == frames_.end()) return false;
    pose = graph_.pose(keyframes_[size_t(it->second.keyframe)].node) * it->second.relative;
    return true;
}

PoseCorrections LoopCloser::corrections() {
    PoseCorrections out;
    for (auto& [index, fused] : frames_) {
        const Pose pose = graph_.pose(keyframes_[size_t(fused.keyframe)].node) * fused.relative;
        const Pose moved = inverseRigid(fused.handed) * pose;
        // Re-fusing a frame costs two frames' fusion: not for a move far below a voxel.
        if (translationMetres(moved) < options_.minCorrectionMetres && rotationDegrees(moved) < options_.minCorrectionDegrees) continue;
        fused.handed = pose;
        out.frames.push_back(index);
        out.poses.push_back(pose);
    }
    return out;
}

namespace {
// The angle between the optical axes of two cameras `relative` apart (inverse(one) * other).
double axisDegrees(const Pose& relative) { return std::acos(std::clamp(relative(2, 2), -1.0, 1.0)) / kRadiansPerDegree; }
}  // namespace

PoseCorrections LoopCloser::frameFused(const LoopClosureFrame& frame) {
    const auto t0 = Clock::now();
    if (!frame.depth) throw Error("loop closure: frame " + std::to_string(frame.index) + " has no depth");
    // The path travelled (a relocalised frame's jump is not travel).
    if (lastPose_ && !relocalisedFrom_) pathMetres_ += translationMetres(inverseRigid(*lastPose_) * frame.cameraToWorld);
    lastPose_ = frame.cameraToWorld;
    if (frame.olderMap) {   // (used below if the frame becomes a keyframe, as wantsOlderMap foresaw)
        ++stats_.olderMapChecks;
        time("older_map", frame.olderMap->milliseconds);
    }

    // A keyframe when the camera moved or turned far enough from the last one (the first frame is one, and so is
    // a relocalised frame: the chain of odometry edges broke there).
    const bool newKeyframe = keyframes_.empty() || relocalisedFrom_.has_value() || farFromLastKeyframe(frame.cameraToWorld);
    PoseCorrections result;
    if (!newKeyframe) {
        const Keyframe& k = keyframes_.back();
        frames_[frame.index] = {int(keyframes_.size()) - 1, inverseRigid(graph_.pose(k.node)) * frame.cameraToWorld, frame.cameraToWorld};
        time("frame", msSince(t0));
        return result;
    }

    auto t = Clock::now();
    Keyframe key;
    key.frame = frame.index;
    key.code = ferns_.encode(ferns_.shrink(*frame.depth, frame.color));
    time("encode", msSince(t));
    t = Clock::now();
    key.features = features_.describe(*frame.depth, frame.color, frame.intrinsics);
    time("features", msSince(t));
    t = Clock::now();
    DepthImage small = *frame.depth;
    int halvings = 0;
    while (small.width > options_.registrationWidth && small.width % 2 == 0 && small.height % 2 == 0) {
        small = gpu::halveTrackingDepth(small, 3.0f * options_.tracker.filterDepthSigma);
        ++halvings;
    }
    key.depth = std::move(small);
    key.intrinsics = pyramidLevelIntrinsics(frame.intrinsics, halvings);
    key.pathMetres = pathMetres_;
    key.node = graph_.addNode(frame.cameraToWorld);
    const int id = int(keyframes_.size());
    if (relocalisedFrom_) {
        // Tied to the keyframe it was relocalised from, as precisely as a registration: tracking against the mesh
        // from that keyframe's pose measured where this frame is relative to it.
        const Keyframe& from = keyframes_[size_t(*relocalisedFrom_)];
        graph_.addEdge({from.node, key.node, inverseRigid(graph_.pose(from.node)) * frame.cameraToWorld,
                        diagonalInformation(options_.loopSigmaMetres, options_.loopSigmaDegrees * kRadiansPerDegree), false});
        relocalisedFrom_.reset();
    } else if (id > 0) {
        const Keyframe& previous = keyframes_.back();
        const Pose motion = inverseRigid(graph_.pose(previous.node)) * frame.cameraToWorld;
        const double sigmaMetres = options_.odometrySigmaMetres + options_.odometrySigmaPerMetre * translationMetres(motion);
        const double sigmaDegrees = options_.odometrySigmaDegrees + options_.odometrySigmaPerDegree * rotationDegrees(motion);
        graph_.addEdge({previous.node, key.node, motion, diagonalInformation(sigmaMetres, sigmaDegrees * kRadiansPerDegree), false});
    }
    keyframes_.push_back(std::move(key));
    frames_[frame.index] = {id, Pose::Identity(), frame.cameraToWorld};
    ++stats_.keyframes;
    time("keyframe", msSince(t));

    const Keyframe& current = keyframes_.back();
    // Against the older map first: the fused model registers far more precisely than one keyframe's depth.
    if (frame.olderMap) {
        if (frame.olderMap->tracked) {
            ++stats_.olderMapMatches;
            lastOlderMapMatch_ = id;
            if (tryOlderMapLoop(current, *frame.olderMap) == LoopOutcome::Closed) {
                result = corrections();
                stats_.framesCorrected += uint32_t(result.frames.size());
                lastVerifiedKeyframe_ = id;
                time("frame", msSince(t0));
                return result;
            }
        }
    }

    // Loop candidates: old enough keyframes whose codes look alike, most alike first (ties: the older first).
    t = Clock::now();
    std::vector<std::pair<double, int>> alike;
    for (int k = 0; k < id; ++k) {
        if (!oldEnoughForLoop(k, current)) continue;
        const double d = RandomFerns::dissimilarity(current.code, keyframes_[size_t(k)].code);
        if (d <= options_.loopDissimilarity) alike.emplace_back(d, k);
    }
    std::sort(alike.begin(), alike.end());
    if (alike.size() > size_t(options_.candidates)) alike.resize(size_t(options_.candidates));
    // The ferns' candidates first (most alike first), then the nearby keyframes (nearest first).
    struct Candidate {
        int keyframe;
        double dissimilarity;
        const char* proposedBy;
    };
    std::vector<Candidate> candidates;
    std::vector<int> byLook;
    for (const auto& [d, k] : alike) {
        candidates.push_back({k, d, "ferns"});
        byLook.push_back(k);
    }
    if (!placeRecentlyVerified(id))
        for (const int k : nearbyKeyframes(current, byLook))
            candidates.push_back({k, RandomFerns::dissimilarity(current.code, keyframes_[size_t(k)].code), "proximity"});
    time("search", msSince(t));
    if (!candidates.empty()) {
        const RegistrationFrame currentFrame = registrationFrame(current.depth, current.intrinsics, options_.tracker, options_.registrationWidth);
        for (const auto& [k, d, proposedBy] : candidates) {
            const LoopOutcome outcome = tryLoop(current, currentFrame, k, d, proposedBy);
            if (outcome == LoopOutcome::Closed) {
                result = corrections();
                stats_.framesCorrected += uint32_t(result.frames.size());
            }
            if (outcome != LoopOutcome::Rejected) {
                lastVerifiedKeyframe_ = id;
                break;
            }
        }
    }
    time("frame", msSince(t0));
    return result;
}

bool LoopCloser::oldEnoughForLoop(int k, const Keyframe& current) const {
    const int newest = int(keyframes_.size()) - 1;
    return k + options_.minKeyframeGap <= newest && keyframes_[size_t(k)].frame + options_.minFrameGap <= current.frame;
}

double LoopCloser::maxDriftMetres(double path) const { return options_.driftBaseMetres + options_.driftPerMetre * path; }

std::vector<int> LoopCloser::nearbyKeyframes(const Keyframe& current, const std::vector<int>& skip) const {
    if (options_.proximityCandidates < 1) return {};
    const Pose currentPose = graph_.pose(current.node);
    std::vector<std::pair<double, int>> near;
    for (int k = 0; k + 1 < int(keyframes_.size()); ++k) {
        const Keyframe& old = keyframes_[size_t(k)];
        if (!oldEnoughForLoop(k, current) || std::find(skip.begin(), skip.end(), k) != skip.end()) continue;
        const Pose apart = inverseRigid(graph_.pose(old.node)) * currentPose;
        const double metres = translationMetres(apart), degrees = axisDegrees(apart);
        // Where the camera can be: no further than tracking can have drifted since the old keyframe (tryLoop's
        // plausibility bound), looking at what it saw.
        const double path = current.pathMetres - old.pathMetres;
        if (metres > maxDriftMetres(path) || degrees > options_.proximityDegrees) continue;
        near.emplace_back(metres / options_.keyframeMetres + degrees / options_.keyframeDegrees, k);   // in keyframe spacings
    }
    std::sort(near.begin(), near.end());
    std::vector<int> out;
    for (const auto& [distance, k] : near) {
        if (int(out.size()) >= options_.proximityCandidates) break;
        out.push_back(k);
    }
    return out;
}

VerificationGates LoopCloser::gates() const {
    return {options_.minInlierShare, options_.maxRmse, options_.symmetricMetres, options_.symmetricDegrees};
}

LoopCloser::LoopOutcome LoopCloser::tryLoop(const Keyframe& current, const RegistrationFrame& currentFrame, int candidate, double dissimilarity,
                                             const char* proposedBy) {
    ++stats_.loopsDetected;
    const Keyframe& old = keyframes_[size_t(candidate)];
    LoopClosureStats::Loop loop;
    loop.frame = current.frame;
    loop.keyframeFrame = old.frame;
    loop.dissimilarity = dissimilarity;
    loop.proposedBy = proposedBy;

    // Verification: the tracker's ICP against the old keyframe's depth, from where tracking thinks the camera is,
    // and from the old keyframe's own pose when that fails (a larger drift than the gates catch).
    auto t = Clock::now();
    const RegistrationFrame oldFrame = registrationFrame(old.depth, old.intrinsics, options_.tracker, options_.registrationWidth);
    const Pose oldPose = graph_.pose(old.node), currentPose = graph_.pose(current.node);
    // Both ways (verifyRegistration): a registration that slid along a weakly constrained direction does not come back.
    const VerifiedRegistration verified = verifyRegistration(currentFrame, oldFrame, oldPose, {currentPose, oldPose}, options_.tracker, gates());
    time("verify", msSince(t));
    if (!verified.match) return rejectLoop(loop, "registration: " + verified.failure);

    // A loop that agrees with the trajectory within what a registration at registration size can tell corrects
    // nothing: no edge, no solve (re-solving for a registration's noise moved poses by its noise: TUM fr1/rpy's and
    // ICL-NUIM's ATE got worse).
    const bool byPlace = loop.proposedBy == "proximity";
    return acceptLoop(current, old, verified.match->cameraToWorld,
                      byPlace ? options_.proximityMinCorrectionMetres : options_.minLoopCorrectionMetres,
                      byPlace ? options_.proximityMinCorrectionDegrees : options_.minLoopCorrectionDegrees, options_.loopSigmaMetres,
                      options_.loopSigmaDegrees, loop);
}

LoopCloser::LoopOutcome LoopCloser::rejectLoop(LoopClosureStats::Loop loop, const std::string& reason) {
    loop.reason = reason;
    ++stats_.loopsRejected;
    ++stats_.rejectedBy[reason.substr(0, reason.find(':'))];
    stats_.loops.push_back(loop);
    return LoopOutcome::Rejected;
}

LoopCloser::LoopOutcome LoopCloser::acceptLoop(const Keyframe& current, const Keyframe& old, const Pose& matched, double minMetres,
                                               double minDegrees, double sigmaMetres, double sigmaDegrees, LoopClosureStats::Loop loop) {
    // Plausibility: no further than tracking can have drifted along the path between the two keyframes.
    const Pose oldPose = graph_.pose(old.node), currentPose = graph_.pose(current.node);
    const Pose correction = inverseRigid(currentPose) * matched;
    loop.correctionMetres = translationMetres(correction);
    loop.correctionDegrees = rotationDegrees(correction);
    const double path = current.pathMetres - old.pathMetres;
    const double maxMetres = maxDriftMetres(path);
    const double maxDegrees = options_.driftBaseDegrees + options_.driftDegreesPerMetre * path;
    if (loop.correctionMetres > maxMetres || loop.correctionDegrees > maxDegrees)
        return rejectLoop(loop, "implausible: moves the camera " + std::to_string(loop.correctionMetres) + " m, " +
                                    std::to_string(loop.correctionDegrees) + " degrees after " + std::to_string(path) + " m of path");

    // Below the caller's threshold the loop agrees with the trajectory: no edge, no solve.
    if (loop.correctionMetres < minMetres && loop.correctionDegrees < minDegrees) {
        ++stats_.loopsConsistent;
        loop.accepted = true;
        loop.reason = "consistent";
        stats_.loops.push_back(loop);
        return LoopOutcome::Consistent;
    }

    // The loop edge, the solve, and the check that the loop now fits.
    const auto t = Clock::now();
    const std::vector<Pose> before = graph_.poses();
    const int edge = graph_.addEdge(
        {old.node, current.node, inverseRigid(oldPose) * matched, diagonalInformation(sigmaMetres, sigmaDegrees * kRadiansPerDegree), true});
    graph_.optimise(50, options_.huber);
    ++stats_.graphSolves;
    const double error = graph_.whitenedError(size_t(edge));
    time("solve", msSince(t));
    if (!(error <= options_.maxLoopError)) {
        graph_.removeLastEdge();
        graph_.setPoses(before);
        return rejectLoop(loop, "graph: the loop stays " + std::to_string(error) + " standard deviations off after the solve");
    }
    ++stats_.loopsAccepted;
    loop.accepted = true;
    stats_.loops.push_back(loop);
    return LoopOutcome::Closed;
}

bool LoopCloser::farFromLastKeyframe(const Pose& cameraToWorld) const {
    const Pose moved = inverseRigid(graph_.pose(keyframes_.back().node)) * cameraToWorld;
    return translationMetres(moved) >= options_.keyframeMetres || rotationDegrees(moved) >= options_.keyframeDegrees;
}

bool LoopCloser::wantsOlderMap(uint32_t frame, const Pose& cameraToWorld) const {
    // A keyframe made now, not right after a relocalisation (its keyframe is tied by that) nor where a loop verified
    // or the older map matched lately (the last proximitySpacing keyframes), with a keyframe old enough for a loop
    // that may see the same surface: looking the same way within olderMapDegrees, within olderMapReachMetres and the
    // drift the path since it allows.
    const int id = int(keyframes_.size());
    const bool matchedLately = lastOlderMapMatch_ >= 0 && id - lastOlderMapMatch_ <= options_.proximitySpacing;
    if (!options_.olderMap || id <= options_.minKeyframeGap || relocalisedFrom_ || placeRecentlyVerified(id) || matchedLately ||
        !farFromLastKeyframe(cameraToWorld))
        return false;
    for (int k = 0; k + options_.minKeyframeGap < id; ++k) {
        const Keyframe& old = keyframes_[size_t(k)];
        if (old.frame + options_.minFrameGap > frame) break;
        const Pose apart = inverseRigid(graph_.pose(old.node)) * cameraToWorld;
        if (axisDegrees(apart) <= options_.olderMapDegrees &&
            translationMetres(apart) <= options_.olderMapReachMetres + maxDriftMetres(pathMetres_ - old.pathMetres))
            return true;
    }
    return false;
}

LoopCloser::LoopOutcome LoopCloser::tryOlderMapLoop(const Keyframe& current, const OlderMapRegistration& registration) {
    // The old keyframe nearest where the older map puts the camera, looking the same way within olderMapDegrees:
    // its pose anchors the loop (the older map is where the graph has the old keyframes).
    const Pose& matched = registration.cameraToWorld;
    int nearest = -1;
    double nearestMetres = 0;
    for (int k = 0; k + 1 < int(keyframes_.size()); ++k) {
        if (!oldEnoughForLoop(k, current)) continue;
        const Pose apart = inverseRigid(graph_.pose(keyframes_[size_t(k)].node)) * matched;
        if (axisDegrees(apart) > options_.olderMapDegrees) continue;
        if (nearest < 0 || translationMetres(apart) < nearestMetres) nearest = k, nearestMetres = translationMetres(apart);
    }
    if (nearest < 0) return LoopOutcome::Rejected;   // the older map in view is not an old keyframe's: no loop to close
    // Only a correction the older map observes is a loop: one it fits clearly better at the matched pose than at the
    // tracked one, and large enough to matter. Else the trajectory agrees with the older map where it can tell (a
    // registration that slides along what the geometry leaves free fits no better): counted as a match, not a loop,
    // and the other candidates are still tried.
    const Pose correction = inverseRigid(graph_.pose(current.node)) * matched;
    if (!(registration.rmse <= options_.olderMapFitGain * registration.rmseAtTracked) ||
        (translationMetres(correction) < options_.olderMapMinCorrectionMetres && rotationDegrees(correction) < options_.olderMapMinCorrectionDegrees))
        return LoopOutcome::Consistent;
    ++stats_.loopsDetected;
    LoopClosureStats::Loop loop;
    loop.frame = current.frame;
    loop.keyframeFrame = keyframes_[size_t(nearest)].frame;
    loop.proposedBy = "older map";
    return acceptLoop(current, keyframes_[size_t(nearest)], matched, 0.0, 0.0, options_.olderMapSigmaMetres, options_.olderMapSigmaDegrees, loop);
}

std::vector<std::pair<int, RelocalisationCandidate>> LoopCloser::placeByFeatures(const LoopClosureFrame& frame, const char* stage) {
    std::vector<std::pair<int, RelocalisationCandidate>> placed;
    if (!frame.depth || keyframes_.empty()) return placed;
    const auto t = Clock::now();
    std::vector<int> matched;   // the keyframes matched against: all of them, or the newest and a moving window
    const size_t limit = size_t(options_.features.matchKeyframes), count = keyframes_.size();
    if (count <= limit) {
        for (size_t k = 0; k < count; ++k) matched.push_back(int(k));
    } else {
        const size_t newest = limit / 4, older = count - newest;
        for (size_t i = 0; i < limit - newest; ++i) matched.push_back(int((featureWindow_ + i) % older));
        featureWindow_ = (featureWindow_ + limit - newest) % older;
        for (size_t k = older; k < count; ++k) matched.push_back(int(k));
    }
    std::vector<const KeyframeFeatures*> described;
    for (const int k : matched) described.push_back(&keyframes_[size_t(k)].features);
    for (const FeatureCandidate& found : features_.propose(frame.color, frame.intrinsics, described)) {
        const int k = matched[size_t(found.keyframe)];   // propose() numbers the keyframes it was given
        placed.push_back({k, {graph_.pose(keyframes_[size_t(k)].node) * inverseRigid(found.keyframeToCamera), true}});
    }
    time(stage, msSince(t));
    return placed;
}

std::vector<RelocalisationCandidate> LoopCloser::placements(const LoopClosureFrame& frame) {
    std::vector<RelocalisationCandidate> poses;
    for (const auto& [k, candidate] : placeByFeatures(frame, "check_features")) poses.push_back(candidate);
    return poses;
}

std::vector<RelocalisationCandidate> LoopCloser::relocalisationCandidates(const LoopClosureFrame& frame) {
    ++stats_.lostFrames;
    lastCandidates_.clear();
    lastByFeatures_.clear();
    std::vector<RelocalisationCandidate> poses;
    if (!frame.depth || keyframes_.empty()) return poses;
    // The features' poses first: they place the camera, where a fern candidate only names a keyframe to start from.
    for (const auto& [k, candidate] : placeByFeatures(frame, "relocalise_features")) {
        lastCandidates_.push_back(k);
        lastByFeatures_.push_back(true);
        poses.push_back(candidate);
        ++stats_.featureCandidates;
    }
    auto t = Clock::now();
    const FernCode code = ferns_.encode(ferns_.shrink(*frame.depth, frame.color));
    std::vector<std::pair<double, int>> alike;
    for (int k = 0; k < int(keyframes_.size()); ++k) {
        const double d = RandomFerns::dissimilarity(code, keyframes_[size_t(k)].code);
        if (d <= options_.relocaliseDissimilarity) alike.emplace_back(d, k);
    }
    std::sort(alike.begin(), alike.end());
    int byFerns = 0;
    for (const auto& [d, k] : alike) {
        if (byFerns >= options_.relocaliseCandidates) break;
        if (std::find(lastCandidates_.begin(), lastCandidates_.end(), k) != lastCandidates_.end()) continue;
        lastCandidates_.push_back(k);
        lastByFeatures_.push_back(false);
        poses.push_back({graph_.pose(keyframes_[size_t(k)].node), false});
        ++byFerns;
    }
    time("relocalise_search", msSince(t));
    return poses;
}

void LoopCloser::relocalisationResult(uint32_t, bool relocalised, int candidatesTried) {
    stats_.relocalisationCandidatesTried += uint32_t(std::max(candidatesTried, 0));
    if (!relocalised) return;
    if (candidatesTried < 1 || size_t(candidatesTried) > lastCandidates_.size())
        throw Error("loop closure: relocalised by candidate " + std::to_string(candidatesTried) + " of " + std::to_string(lastCandidates_.size()));
    ++stats_.relocalisations;
    if (lastByFeatures_[size_t(candidatesTried) - 1]) ++stats_.relocalisationsByFeatures;
    relocalisedFrom_ = lastCandidates_[size_t(candidatesTried) - 1];
}

namespace {

constexpr char kLoopsMagic[8] = {'V', 'K', 'L', 'O', 'O', 'P', 'S', 0};
constexpr uint32_t kLoopsVersion = 2;   // 2: keyframes' ORB features

struct Out {
    std::string bytes;
    template <class T>
    void put(const T& v) { bytes.append(reinterpret_cast<const char*>(&v), sizeof(T)); }
    void pose(const Pose& p) { for (int r = 0; r < 4; ++r) for (int c = 0; c < 4; ++c) put(p(r, c)); }
};

struct In {
    const std::string& bytes;
    size_t at = 0;
    std::string file;
    template <class T>
    T get() {
        if (bytes.size() - at < sizeof(T)) throw Error("loop closure: " + file + " is truncated (at byte " + std::to_string(at) + " of its state)");
        T v;
        std::memcpy(&v, bytes.data() + at, sizeof(T));
        at += sizeof(T);
        return v;
    }
    Pose pose() {
        Pose p;
        for (int r = 0; r < 4; ++r) for (int c = 0; c < 4; ++c) p(r, c) = get<double>();
        return p;
    }
    uint32_t count(size_t bytesEach) {   // a count that the remaining bytes can hold
        const uint32_t n = get<uint32_t>();
        if (bytesEach > 0 && n > (bytes.size() - at) / bytesEach) throw Error("loop closure: " + file + " holds a count (" + std::to_string(n) + ") its bytes cannot");
        return n;
    }
};

}  // namespace

void LoopCloser::save(const std::filesystem::path& path, uint64_t mapId) const {
    Out o;
    o.put(pathMetres_);
    o.put(uint8_t(lastPose_.has_value()));
    o.pose(lastPose_.value_or(Pose::Identity()));
    o.put(uint32_t(keyframes_.size()));
    for (const Keyframe& k : keyframes_) {
        o.put(k.frame);
        o.put(int32_t(k.node));
        o.put(uint32_t(k.code.size()));
        o.bytes.append(reinterpret_cast<const char*>(k.code.data()), k.code.size());
        o.put(int32_t(k.depth.width));
        o.put(int32_t(k.depth.height));
        o.put(k.intrinsics.fx), o.put(k.intrinsics.fy), o.put(k.intrinsics.cx), o.put(k.intrinsics.cy);
        o.put(k.pathMetres);
        o.bytes.append(reinterpret_cast<const char*>(k.depth.meters.data()), k.depth.meters.size() * sizeof(float));
        o.put(uint32_t(k.features.count()));
        o.bytes.append(reinterpret_cast<const char*>(k.features.points.data()), k.features.points.size() * sizeof(float));
        o.bytes.append(reinterpret_cast<const char*>(k.features.descriptors.data()), k.features.descriptors.size());
    }
    o.put(uint32_t(graph_.nodes()));
    for (const Pose& p : graph_.poses()) o.pose(p);
    o.put(uint32_t(graph_.edges().size()));
    for (const PoseGraphEdge& e : graph_.edges()) {
        o.put(int32_t(e.from)), o.put(int32_t(e.to));
        o.pose(e.measured);
        for (int i = 0; i < 36; ++i) o.put(e.information.data()[i]);
        o.put(uint8_t(e.loop));
    }
    o.put(uint32_t(frames_.size()));
    for (const auto& [index, f] : frames_) {
        o.put(index);
        o.put(int32_t(f.keyframe));
        o.pose(f.relative);
        o.pose(f.handed);
    }
    std::string packed(ZSTD_compressBound(o.bytes.size()), '\0');
    const size_t n = ZSTD_compress(packed.data(), packed.size(), o.bytes.data(), o.bytes.size(), 3);
    if (ZSTD_isError(n)) throw Error(std::string("loop closure: compressing the state failed: ") + ZSTD_getErrorName(n));
    packed.resize(n);
    Out header;
    header.bytes.append(kLoopsMagic, sizeof kLoopsMagic);
    header.put(kLoopsVersion);
    header.put(mapId);
    header.put(uint64_t(packed.size()));
    header.put(map::crc32(packed.data(), packed.size()));
    const std::filesystem::path tmp = path.string() + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out.write(header.bytes.data(), std::streamsize(header.bytes.size()));
        out.write(packed.data(), std::streamsize(packed.size()));
        out.close();
        if (!out) throw Error("loop closure: cannot write " + tmp.string());
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw Error("loop closure: cannot rename " + tmp.string() + " to " + path.string() + ": " + ec.message());
}

void LoopCloser::load(const std::filesystem::path& path, uint64_t mapId) {
    const std::string file = path.string();
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("loop closure: cannot open " + file);
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    In h{all, 0, file};
    if (all.size() < sizeof kLoopsMagic || std::memcmp(all.data(), kLoopsMagic, sizeof kLoopsMagic) != 0)
        throw Error("loop closure: " + file + " is not a loop-closure file (no VKLOOPS header)");
    h.at = sizeof kLoopsMagic;
    const uint32_t version = h.get<uint32_t>();
    if (version < 1 || version > kLoopsVersion)
        throw Error("loop closure: " + file + " is version " + std::to_string(version) + "; this vkmesh reads versions 1 to " +
                    std::to_string(kLoopsVersion));
    if (h.get<uint64_t>() != mapId) throw Error("loop closure: " + file + " belongs to another map (its map id differs from the map's)");
    const uint64_t packedBytes = h.get<uint64_t>();
    const uint32_t crc = h.get<uint32_t>();
    if (all.size() - h.at != packedBytes) throw Error("loop closure: " + file + " is truncated or has trailing bytes");
    if (map::crc32(all.data() + h.at, packedBytes) != crc) throw Error("loop closure: " + file + " is corrupt (CRC mismatch)");
    const unsigned long long rawBytes = ZSTD_getFrameContentSize(all.data() + h.at, packedBytes);
    if (rawBytes == ZSTD_CONTENTSIZE_ERROR || rawBytes == ZSTD_CONTENTSIZE_UNKNOWN || rawBytes > (uint64_t(1) << 34))
        throw Error("loop closure: " + file + " holds no readable zstd frame");
    std::string raw(rawBytes, '\0');
    const size_t n = ZSTD_decompress(raw.data(), raw.size(), all.data() + h.at, packedBytes);
    if (ZSTD_isError(n) || n != rawBytes) throw Error("loop closure: " + file + ": its state does not decompress");

    In r{raw, 0, file};
    LoopCloser loaded(options_);
    loaded.pathMetres_ = r.get<double>();
    const bool hasLast = r.get<uint8_t>() != 0;
    const Pose last = r.pose();
    if (hasLast) loaded.lastPose_ = last;
    const uint32_t keyframes = r.count(40);
    for (uint32_t i = 0; i < keyframes; ++i) {
        Keyframe k;
        k.frame = r.get<uint32_t>();
        k.node = r.get<int32_t>();
        const uint32_t codeSize = r.count(1);
        k.code.assign(raw.begin() + std::ptrdiff_t(r.at), raw.begin() + std::ptrdiff_t(r.at + codeSize));
        r.at += codeSize;
        k.depth.width = r.get<int32_t>();
        k.depth.height = r.get<int32_t>();
        k.intrinsics.fx = r.get<float>(), k.intrinsics.fy = r.get<float>(), k.intrinsics.cx = r.get<float>(), k.intrinsics.cy = r.get<float>();
        k.intrinsics.width = k.depth.width, k.intrinsics.height = k.depth.height;
        k.pathMetres = r.get<double>();
        if (k.depth.width <= 0 || k.depth.height <= 0 || k.depth.width > 16384 || k.depth.height > 16384 ||
            size_t(k.depth.width) * size_t(k.depth.height) * sizeof(float) > raw.size() - r.at)
            throw Error("loop closure: " + file + ": keyframe " + std::to_string(i) + " has a bad image size");
        k.depth.meters.resize(size_t(k.depth.width) * size_t(k.depth.height));
        std::memcpy(k.depth.meters.data(), raw.data() + r.at, k.depth.meters.size() * sizeof(float));
        r.at += k.depth.meters.size() * sizeof(float);
        if (version >= 2) {   // version 1 keyframes have no features: the ferns alone propose them
            const uint32_t features = r.count(3 * sizeof(float) + 32);
            k.features.points.resize(size_t(features) * 3);
            k.features.descriptors.resize(size_t(features) * 32);
            std::memcpy(k.features.points.data(), raw.data() + r.at, k.features.points.size() * sizeof(float));
            r.at += k.features.points.size() * sizeof(float);
            std::memcpy(k.features.descriptors.data(), raw.data() + r.at, k.features.descriptors.size());
            r.at += k.features.descriptors.size();
        }
        loaded.keyframes_.push_back(std::move(k));
    }
    const uint32_t nodes = r.count(128);
    for (uint32_t i = 0; i < nodes; ++i) loaded.graph_.addNode(r.pose());
    const uint32_t edges = r.count(128 + 288 + 9);
    for (uint32_t i = 0; i < edges; ++i) {
        PoseGraphEdge e;
        e.from = r.get<int32_t>(), e.to = r.get<int32_t>();
        e.measured = r.pose();
        for (int j = 0; j < 36; ++j) e.information.data()[j] = r.get<double>();
        e.loop = r.get<uint8_t>() != 0;
        loaded.graph_.addEdge(e);   // checks the nodes and the information
    }
    const uint32_t frames = r.count(264);
    for (uint32_t i = 0; i < frames; ++i) {
        const uint32_t index = r.get<uint32_t>();
        FusedFrame f;
        f.keyframe = r.get<int32_t>();
        f.relative = r.pose();
        f.handed = r.pose();
        if (f.keyframe < 0 || size_t(f.keyframe) >= loaded.keyframes_.size())
            throw Error("loop closure: " + file + ": frame " + std::to_string(index) + " follows keyframe " + std::to_string(f.keyframe) + " of " +
                        std::to_string(loaded.keyframes_.size()));
        loaded.frames_[index] = f;
    }
    for (const Keyframe& k : loaded.keyframes_)
        if (k.node < 0 || size_t(k.node) >= loaded.graph_.nodes())
            throw Error("loop closure: " + file + ": a keyframe's node " + std::to_string(k.node) + " is not in the graph");
    if (r.at != raw.size()) throw Error("loop closure: " + file + " has bytes after its state");
    loaded.stats_.keyframes = uint32_t(loaded.keyframes_.size());
    *this = std::move(loaded);
}

}  // namespace vkmesh::slam
