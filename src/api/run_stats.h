// What a run did, counted by the Mapper (api/mapper.h) as it goes: per-frame times and counts, capacity
// events, tracking, relocalisation, loop closure and the corrections it re-fused, warnings. A plain value: the
// CLI writes it as `vkmesh fuse --stats` JSON and Python returns it as a dict, both through
// runStatsJson (api/run_stats_json.h), so that every front end reports the same keys from the same counts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/loop_closure.h"
#include "core/types.h"

namespace vkmesh {

namespace gpu {
struct FrameReport;
struct TrackingReport;
struct CorrectionReport;
}  // namespace gpu

// Lists kept for the report (lost frames, relocalisations, warnings) stop growing here: a run of a million
// frames does not keep a million lines.
inline constexpr size_t kRunStatsListLimit = 1000;

struct RunStats {
    // Frames: fused (integrated), or skipped (unreadable, no valid depth); a lost frame is neither.
    size_t integrated = 0, skipped = 0;
    size_t framesWithColor = 0;   // frames that came with a colour image the volume fused

    // Per fused frame: GPU ms per stage ("mesh_total": the mesh stages' sum), per pass (GpuVolumeConfig::
    // timePasses; a pass recorded twice in a frame counts its sum), the counts behind the work, and wall ms.
    std::map<std::string, std::vector<double>> stageMs, passMs, perFrameCounts;
    std::vector<double> frameWallMs;
    // Capacity events summed over the frames; what grew, frame by frame; frames run again after growing.
    uint64_t hashFull = 0, poolExhausted = 0, framesTouchingMoreThanCapacity = 0;
    std::map<std::string, uint64_t> events;
    size_t framesDeferred = 0;
    std::vector<std::string> growth;
    std::vector<std::string> warnings;   // at most kRunStatsListLimit
    // Paging (GpuVolumeConfig::residentBlocks, docs/PAGING.md): blocks and bytes moved each way, host ms per frame,
    // blocks on the host after each frame, frames whose camera reached more blocks than the budget.
    struct Paging {
        uint64_t blocksIn = 0, blocksOut = 0, bytesIn = 0, bytesOut = 0;
        size_t framesOverBudget = 0;
        uint32_t mostPaged = 0;
        std::vector<double> ms, blocksPaged;
    } paging;

    // Tracking (frames integrated without a pose, after the first of a run).
    struct Tracking {
        bool enabled = false;
        std::vector<double> ms, gpuMs, iterations, submissions;
        std::vector<double> rmse, inlierShare;          // tracked frames only
        std::map<std::string, std::vector<double>> stageMs;
        size_t modelDraws = 0;                          // frames whose tracking drew the mesh
        size_t lostFrames = 0;
        size_t relocalisedFrames = 0;
        size_t tentativeFrames = 0;                     // tracked from an unconfirmed relocalisation, not fused
        struct Lost {
            uint32_t frame = 0;
            std::string reason;
        };
        std::vector<Lost> lost;                          // at most kRunStatsListLimit
        // Every tracked run's frame after the first, with its verdict and what it was decided on (--stats
        // "tracking.per_frame"): how a user sees why a frame was kept or lost, and what thresholds separate them.
        struct Verdict {
            uint32_t frame = 0;
            // "tracked", "relocalised" (confirmed: fused), "tentative" (tracked from a relocalisation not yet
            // confirmed: not fused) or "lost"
            const char* status = "tracked";
            double inlierShare = 0, rmse = 0, conditioning = 0;
            std::string reason;                          // a lost or tentative frame's; a relocalised one's loss
        };
        std::vector<Verdict> verdicts;                   // at most kRunStatsListLimit
        // Metres between the tracked position and the frame's reference (the dataset's pose, where it has one).
        std::vector<double> positionError;
    } tracking;

    // Loop closure: the loop closer's own counts, the relocalisation attempts, what the corrections re-fused,
    // and the final poses' error against the references (after every correction).
    struct Relocalisation {
        uint32_t frame = 0;
        bool relocalised = false;
        size_t candidates = 0;
        size_t placedCandidates = 0;     // of them, poses the frame's features placed (RelocalisationCandidate::placed)
        int tried = 0;
        bool placed = false;             // the accepted candidate was placed by the features and tracking agreed
        // The match of the accepted candidate (or of a refused one): its inlier share and RMSE, and why it was refused.
        double inlierShare = 0, rmse = 0;
        std::string reason;
        bool tentative = false;          // a candidate was accepted as the hypothesis to confirm;
        int64_t confirmedAt = -1;        //  confirmed at this frame (relocalised true then),
        std::string refusedBy;           //  or refused later, and why
    };
    std::vector<Relocalisation> relocalisations;      // at most kRunStatsListLimit
    uint32_t framesRefused = 0, observationsDropped = 0;
    double correctionMilliseconds = 0;
    std::optional<LoopClosureStats> loopClosure;       // a run with a loop closer
    std::vector<double> finalPositionError;            // filled by Mapper::finish()

    double fusionSeconds = 0;   // wall time from the first frame to the end of Mapper::finish()

    // Accumulation, as the Mapper does it.
    void addWarning(const std::string& warning) {
        if (warnings.size() < kRunStatsListLimit) warnings.push_back(warning);
    }
    // A fused frame's report (its number for the growth lines), with touchedCapacity to count overflowing frames.
    void addFusedFrame(uint32_t frame, const gpu::FrameReport& report, double wallMs, bool incremental, uint32_t touchedCapacity,
                       uint32_t vertexCapacity);
    void addTracking(const gpu::TrackingReport& report);
    void addCorrections(const gpu::CorrectionReport& report);
};

// The median, mean and max of a series (what --stats prints for every series), and a nearest-rank percentile.
struct SeriesSummary {
    double median = 0, mean = 0, max = 0;
    bool empty = true;
};
SeriesSummary summarize(std::vector<double> values);
double percentile(std::vector<double> values, double share);

}  // namespace vkmesh
