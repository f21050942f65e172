#include "api/run_stats_json.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vkmesh {

using json = nlohmann::json;

namespace {

json positionErrorJson(const std::vector<double>& errors) {
    double squared = 0;
    for (double e : errors) squared += e * e;
    return {{"frames", errors.size()},
            {"rmse", errors.empty() ? 0.0 : std::sqrt(squared / double(errors.size()))},
            {"max", errors.empty() ? 0.0 : *std::max_element(errors.begin(), errors.end())}};
}

const char* colorModeName(ColorFusion mode) {
    switch (mode) {
        case ColorFusion::Off: return "off";
        case ColorFusion::Recent: return "recent";
        default: return "average";
    }
}

json trackingJson(const Mapper& mapper, const RunStats& s) {
    const RunStats::Tracking& t = s.tracking;
    if (!t.enabled) return {{"enabled", false}};
    const gpu::TrackerOptions& options = mapper.tracker() ? mapper.tracker()->options() : mapper.options().tracker;
    json ms = seriesJson(t.ms);
    ms["p90"] = percentile(t.ms, 0.9);
    json gpuMs = seriesJson(t.gpuMs);
    gpuMs["p90"] = percentile(t.gpuMs, 0.9);
    json stages = json::object();
    for (const auto& [name, values] : t.stageMs) stages[name] = seriesJson(values);
    json lost = json::array();
    for (const auto& l : t.lost) lost.push_back({{"frame", l.frame}, {"reason", l.reason}});
    json verdicts = json::array();
    for (const auto& v : t.verdicts)
        verdicts.push_back({{"frame", v.frame}, {"status", v.status}, {"inlier_share", v.inlierShare}, {"rmse_m", v.rmse},
                            {"conditioning", v.conditioning}, {"reason", v.reason}});
    json its = seriesJson(t.iterations);
    its["total"] = std::accumulate(t.iterations.begin(), t.iterations.end(), 0.0);
    return {{"enabled", true},
            {"frames_tracked", t.ms.size() - t.lostFrames - t.tentativeFrames},
            {"lost_frames", t.lostFrames},
            {"lost", lost},
            {"ms_per_frame", ms},
            {"gpu_ms_per_frame", gpuMs},
            {"gpu_ms_stages", stages},
            {"iterations", its},
            {"submissions_per_frame", seriesJson(t.submissions)},
            {"rmse_m", seriesJson(t.rmse)},
            {"inlier_share", seriesJson(t.inlierShare)},
            {"color_weight", options.colorWeight},
            {"solve", options.solveOnGpu ? "gpu" : "host"},
            // solve "gpu": tracking, fusion and meshing are one submission per frame, so ms_per_frame (wall) holds
            // the fusion and meshing too
            {"fused_in_tracking_submission", options.solveOnGpu},
            {"downsample", mapper.hasVolume() ? gpu::trackingDownsample(options, mapper.volume().config().imageWidth) : options.downsample},
            // frames whose tracking drew the mesh; the others reused the last maps (--track-model-reuse)
            {"model_draws", t.modelDraws},
            {"model_reuse_frames", options.modelReuseFrames},
            // against the frames' reference poses where they have them (the first frame's is shared: no alignment); metres
            {"position_error_m", positionErrorJson(t.positionError)},
            {"relocalised_frames", t.relocalisedFrames},
            // tracked from a relocalisation not yet confirmed, not fused (docs/LOOP_CLOSURE.md, "Relocalisation")
            {"tentative_frames", t.tentativeFrames},
            // every tracked frame's verdict and the numbers it was decided on (at most the first 1000 frames)
            {"per_frame", verdicts}};
}

json loopClosureJson(const Mapper& mapper, const RunStats& s) {
    if (!s.loopClosure) return {{"enabled", false}};
    const LoopClosureStats& l = *s.loopClosure;
    json ms = json::object();
    for (const auto& [stage, sumCount] : l.milliseconds)
        ms[stage] = {{"total", sumCount.first}, {"count", sumCount.second}, {"mean", sumCount.second ? sumCount.first / sumCount.second : 0.0}};
    ms["correction"] = {{"total", s.correctionMilliseconds}, {"count", s.framesRefused},
                        {"mean", s.framesRefused ? s.correctionMilliseconds / s.framesRefused : 0.0}};
    json loops = json::array();
    for (const auto& loop : l.loops) {
        if (loops.size() >= kRunStatsListLimit) break;
        loops.push_back({{"frame", loop.frame}, {"keyframe_frame", loop.keyframeFrame}, {"dissimilarity", loop.dissimilarity},
                         {"proposed_by", loop.proposedBy}, {"accepted", loop.accepted}, {"reason", loop.reason}, {"correction_m", loop.correctionMetres},
                         {"correction_deg", loop.correctionDegrees}});
    }
    json rejectedBy = json::object();
    for (const auto& [reason, n] : l.rejectedBy) rejectedBy[reason] = n;
    json relocalisation = json::array();
    for (const auto& r : s.relocalisations)
        relocalisation.push_back({{"frame", r.frame}, {"relocalised", r.relocalised}, {"candidates", r.candidates},
                                  {"placed_candidates", r.placedCandidates}, {"placed", r.placed}, {"tried", r.tried},
                                  {"inlier_share", r.inlierShare}, {"rmse_m", r.rmse}, {"reason", r.reason}, {"tentative", r.tentative},
                                  {"confirmed_at", r.confirmedAt >= 0 ? json(r.confirmedAt) : json(nullptr)}, {"refused_by", r.refusedBy}});
    return {{"enabled", true},
            {"keyframes", l.keyframes},
            {"loops_detected", l.loopsDetected},
            {"loops_accepted", l.loopsAccepted},
            {"loops_rejected", l.loopsRejected},
            {"loops_consistent", l.loopsConsistent},
            {"rejected_by", rejectedBy},
            {"lost_frames", l.lostFrames},
            {"relocalisations", l.relocalisations},
            {"relocalisation_candidates_tried", l.relocalisationCandidatesTried},
            {"feature_candidates", l.featureCandidates},
            {"relocalisations_by_features", l.relocalisationsByFeatures},
            {"frames_corrected", l.framesCorrected},
            {"older_map_checks", l.olderMapChecks},
            {"older_map_matches", l.olderMapMatches},
            {"frames_refused", s.framesRefused},
            {"observations_dropped", s.observationsDropped},
            {"graph_solves", l.graphSolves},
            {"ms", ms},
            {"loops", loops},
            {"relocalisation", relocalisation},
            // the final poses (every loop's correction applied) against the references, as tracking's position_error_m
            {"position_error_m", positionErrorJson(s.finalPositionError)},
            {"corrections_per_frame", mapper.options().correctionsPerFrame}};
}

}  // namespace

json seriesJson(const std::vector<double>& values) {
    const SeriesSummary s = summarize(values);
    if (s.empty) return json{{"median", nullptr}, {"mean", nullptr}, {"max", nullptr}};
    return json{{"median", s.median}, {"mean", s.mean}, {"max", s.max}};
}

json runStatsJson(const Mapper& mapper) {
    const RunStats s = mapper.stats();
    const vk::Context& context = mapper.context();
    const gpu::GpuVolumeConfig& c = mapper.hasVolume() ? mapper.volume().config() : mapper.options().volume;
    const bool incremental = c.meshMode == gpu::MeshMode::Incremental;
    const bool fuseColor = c.params.colorFusion != ColorFusion::Off;
    json stats;
    stats["device"] = context.info().name;
    stats["unified_memory"] = context.unifiedMemory();   // the frame's images written in place, no staging copy
    stats["int64_atomics"] = context.int64Atomics();     // the block hash's path (docs/HASH.md)
    stats["mode"] = incremental ? "incremental" : "baseline";
    stats["refine"] = c.refine;
    stats["refine_epsilon_voxels"] = c.refineEpsilonVoxels;
    stats["lock_free"] = c.lockFree;
    stats["frames"] = {{"integrated", s.integrated}, {"skipped", s.skipped}};
    stats["voxel_size"] = c.params.voxelSize;
    stats["truncation_m"] = c.params.truncation();
    stats["allocation_stride"] = c.params.allocationStride;
    stats["allocation_tiles"] = c.params.allocationTiles;
    stats["max_depth"] = c.params.maxDepth;
    stats["recycling"] = {{"keep_radius", c.keepRadius}, {"recycle", c.recycle}, {"recycle_after_frames", c.recycleAfterFrames},
                          {"starve_weight", c.starveWeight}};
    // Persistent state per cube: TSDF (sdf + weight) + cube state + 3 edge-vertex slots (+ colour).
    stats["bytes_per_cube"] = (incremental ? 24 : 8) + (fuseColor ? 4 : 0);
    stats["color"] = {{"fused", fuseColor},
                      {"mode", colorModeName(c.params.colorFusion)},
                      {"recency", c.params.colorRecency},
                      {"frames_with_color", s.framesWithColor}};
    if (c.residentBlocks > 0) {
        const RunStats::Paging& p = s.paging;
        stats["paging"] = {{"resident_blocks", c.residentBlocks}, {"blocks_in", p.blocksIn}, {"blocks_out", p.blocksOut},
                           {"bytes_in", p.bytesIn}, {"bytes_out", p.bytesOut}, {"frames_over_budget", p.framesOverBudget},
                           {"most_blocks_paged", p.mostPaged}, {"ms_per_frame", seriesJson(p.ms)},
                           {"blocks_paged_per_frame", seriesJson(p.blocksPaged)}};
    }
    stats["capacities"] = {{"grow", c.growCapacities}, {"blocks", c.blockCapacity}, {"hash_slots", c.hashCapacity},
                           {"touched", c.touchedCapacity}, {"retype", c.retypeCapacity},
                           {"vertices", c.vertexCapacity}, {"triangle_chunks", c.chunkCapacity}};
    stats["tracking"] = trackingJson(mapper, s);
    stats["loop_closure"] = loopClosureJson(mapper, s);
    stats["warnings"] = s.warnings;
    if (const FrameStore* store = mapper.frameStore()) {
        const FrameStoreStats fs = store->stats();
        stats["frame_store"] = {{"frames", fs.frames}, {"frames_spilled", fs.framesSpilled}, {"raw_bytes", fs.rawBytes},
                                {"compressed_bytes", fs.compressedBytes}, {"bytes_in_memory", fs.bytesInMemory},
                                {"bytes_on_disk", fs.bytesOnDisk},
                                {"bytes_per_frame", fs.frames ? double(fs.compressedBytes) / fs.frames : 0.0},
                                {"pending_corrections", mapper.pendingCorrections()}};
    }
    if (!mapper.hasVolume()) return stats;   // nothing on the GPU before the first frame

    const gpu::GpuVolume& volume = mapper.volume();
    const gpu::Counters k = volume.readCounters();
    stats["blocks"] = {{"in_use", k.blocksInUse}, {"capacity", c.blockCapacity}, {"hash_capacity", c.hashCapacity},
                       {"hash_entries", k.hashEntries}, {"hash_tombstones", k.hashTombstones}};
    if (incremental)
        stats["heaps"] = {{"vertices", {{"capacity", c.vertexCapacity}, {"live", k.verticesInUse}, {"free", k.vertexFreeTop},
                                        {"high_water", k.vertexHighWater}}},
                          {"triangle_chunks", {{"capacity", c.chunkCapacity}, {"live", k.chunksInUse}, {"free", k.chunkFreeTop},
                                               {"high_water", k.chunkHighWater}}},
                          {"live_triangles", k.liveTriangles}};
    json gpuMs = json::object();
    for (const auto& [name, values] : s.stageMs) gpuMs[name] = seriesJson(values);
    stats["gpu_ms_per_frame"] = gpuMs;
    if (c.timePasses) {
        json perPass = json::object();
        for (const auto& [name, values] : s.passMs) perPass[name] = seriesJson(values);
        stats["gpu_ms_per_pass"] = perPass;
    }
    if (auto m = s.stageMs.find("mesh_total"); m != s.stageMs.end()) {
        // The end of the sequence: the mesh is largest there (the peer's full extraction is timed there too).
        const std::vector<double>& all = m->second;
        std::vector<double> tail(all.end() - std::max<ptrdiff_t>(1, ptrdiff_t(all.size()) / 10), all.end());
        stats["gpu_ms_mesh_last_10pct_frames"] = seriesJson(tail);
    }
    json counts = json::object();
    for (const auto& [name, values] : s.perFrameCounts) counts[name] = seriesJson(values);
    stats["per_frame_counts"] = counts;
    stats["wall_ms_per_frame"] = seriesJson(s.frameWallMs);
    stats["wall_s_fusion_total"] = s.fusionSeconds;
    json pools = json::object();
    size_t total = 0;
    for (const auto& p : volume.pools()) pools[p.name] = p.bytes, total += p.bytes;
    stats["gpu_pool_bytes"] = pools;
    stats["gpu_bytes_total"] = total;
    json capacityEvents = {{"hash_full", s.hashFull}, {"pool_exhausted", s.poolExhausted},
                           {"frames_touching_more_than_capacity", s.framesTouchingMoreThanCapacity}};
    for (const auto& [name, n] : s.events) capacityEvents[name] = n;
    capacityEvents["frames_deferred"] = s.framesDeferred;   // run again after growing what their allocation overflowed
    stats["capacity_events"] = capacityEvents;
    stats["capacity_growth"] = s.growth;
    return stats;
}

json mergeReportJson(const MergeReport& r) {
    json inputs = json::array();
    for (const MergeInputReport& in : r.inputs)
        inputs.push_back({{"path", in.path}, {"blocks", in.blocks}, {"frames_integrated", in.framesIntegrated},
                          {"frame_store", in.frameStore}, {"frames_stored", in.framesStored}});
    json j;
    j["inputs"] = inputs;
    j["blocks"] = {{"merged", r.blocks}, {"shared", r.sharedBlocks}};
    j["observed_corners"] = r.corners;
    j["frames_integrated"] = r.framesIntegrated;
    j["frame_store"] = {{"path", r.frameStorePath}, {"frames", r.framesStored}, {"renumbered", r.framesRenumbered}};
    j["mesh"] = {{"vertices", r.meshVertices}, {"triangles", r.meshTriangles}};
    j["ms"] = {{"read", r.readMs}, {"merge", r.mergeMs}, {"rebuild", r.rebuildMs}, {"save", r.saveMs}, {"tiles", r.tilesMs}};
    j["tiles"] = {{"count", r.tiles}, {"triangles", r.tileTriangles}, {"max_blocks", r.tileBlocksMax}};
    j["warnings"] = r.warnings;
    return j;
}

}  // namespace vkmesh
