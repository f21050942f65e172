#include "api/run_stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu/tracking/pose_tracker.h"

namespace vkmesh {

void RunStats::addFusedFrame(uint32_t frame, const gpu::FrameReport& report, double wallMs, bool incremental, uint32_t touchedCapacity,
                             uint32_t vertexCapacity) {
    ++integrated;
    frameWallMs.push_back(wallMs);
    double meshMs = 0;
    for (const auto& [name, ms] : report.stageMs) {
        stageMs[name].push_back(ms);
        if (name.rfind("mesh_", 0) == 0) meshMs += ms;
    }
    if (incremental && !report.stageMs.empty()) stageMs["mesh_total"].push_back(meshMs);
    std::map<std::string, double> framePassMs;   // a pass recorded more than once in the frame: its sum
    for (const auto& [name, ms] : report.passMs) framePassMs[name] += ms;
    for (const auto& [name, ms] : framePassMs) passMs[name].push_back(ms);
    const gpu::Counters& c = report.counters;
    perFrameCounts["touched_blocks"].push_back(c.touchedCount);
    perFrameCounts["dispatches"].push_back(report.dispatches);
    // Allocation's work: blocks the band walks visited, and the visits that had to ask the hash.
    perFrameCounts["block_visits"].push_back(c.blockRequests);
    perFrameCounts["hash_requests"].push_back(c.blockRequests - c.blocksShared);
    perFrameCounts["dirty_blocks"].push_back(c.dirtyCount);
    perFrameCounts["cubes_retyped"].push_back(c.cubesRetyped);
    perFrameCounts["cubes_listed"].push_back(c.retypeCount);   // the candidates claim classified
    perFrameCounts["triangles_created"].push_back(c.trianglesCreated);
    perFrameCounts["vertices_moved"].push_back(c.movedCount);
    hashFull += c.hashFull;
    poolExhausted += c.poolExhausted;
    framesTouchingMoreThanCapacity += c.touchedCount > touchedCapacity;
    for (const auto& [name, value] :
         {std::pair<const char*, uint32_t>{"vertex_heap_exhausted", c.vertexExhausted},
          {"chunk_heap_exhausted", c.chunkExhausted},
          {"triangles_not_built", c.trianglesInvalid},
          {"retype_deferred", c.retypeDeferred},
          {"gc_candidates_dropped", c.candidateCount > vertexCapacity ? c.candidateCount - vertexCapacity : 0u},
          {"out_of_range", c.outOfRange},
          {"ray_truncated", c.rayTruncated},
          {"outside_keep_radius", c.outsideRadius},
          {"blocks_retired", c.blocksRetired},
          {"blocks_starved", c.blocksStarved},
          {"blocks_freed", c.blocksFreed},
          {"recycle_deferred", c.recycleDeferred},
          {"hash_rebuilds", c.hashRebuilt},
          {"rehash_lost", c.rehashLost}})
        events[name] += value;
    paging.blocksIn += report.paging.blocksIn;
    paging.blocksOut += report.paging.blocksOut;
    paging.bytesIn += report.paging.bytesIn;
    paging.bytesOut += report.paging.bytesOut;
    paging.framesOverBudget += report.paging.overBudget > 0;
    paging.mostPaged = std::max(paging.mostPaged, report.paging.blocksPaged);
    paging.ms.push_back(report.paging.milliseconds);
    paging.blocksPaged.push_back(report.paging.blocksPaged);
    for (const auto& w : report.warnings) addWarning("frame " + std::to_string(frame) + ": " + w);
    for (const auto& g : report.growth) growth.push_back("frame " + std::to_string(frame) + ": " + g);
    events["heap_growths"] += std::count_if(report.growth.begin(), report.growth.end(),
                                            [](const std::string& g) { return g.rfind("mesh heaps", 0) == 0; });
    framesDeferred += report.deferredAttempts;
}

void RunStats::addTracking(const gpu::TrackingReport& tr) {
    tracking.ms.push_back(tr.milliseconds);
    tracking.gpuMs.push_back(tr.gpuMilliseconds);
    for (const auto& [name, ms] : tr.gpuStageMilliseconds) tracking.stageMs[name].push_back(ms);
    tracking.iterations.push_back(tr.iterations);
    tracking.submissions.push_back(tr.submissions);
    tracking.modelDraws += tr.modelDrawn;
    if (tr.tracked) {
        tracking.rmse.push_back(tr.rmse);
        tracking.inlierShare.push_back(tr.inlierShare());
    }
}

void RunStats::addCorrections(const gpu::CorrectionReport& r) {
    framesRefused += r.framesRefused;
    observationsDropped += r.observationsDropped;
    correctionMilliseconds += r.milliseconds;
}

SeriesSummary summarize(std::vector<double> values) {
    SeriesSummary s;
    if (values.empty()) return s;
    s.empty = false;
    s.mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
    std::sort(values.begin(), values.end());
    s.median = values.size() % 2 ? values[values.size() / 2] : 0.5 * (values[values.size() / 2 - 1] + values[values.size() / 2]);
    s.max = values.back();
    return s;
}

double percentile(std::vector<double> values, double share) {
    if (values.empty()) return 0;
    std::sort(values.begin(), values.end());
    size_t rank = size_t(std::ceil(share * double(values.size())));
    return values[std::clamp<size_t>(rank, 1, values.size()) - 1];
}

}  // namespace vkmesh
