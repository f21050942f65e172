// GpuVolume's paging (docs/PAGING.md; GpuVolumeConfig::residentBlocks): blocks move between GPU memory and the host
// between frames (PagingStage), so that a paged run's map and mesh are the unpaged run's bit for bit.
//
//  - Out, after a frame, while more than residentBlocks blocks are live: the blocks the frame's camera cannot reach,
//    least recently seen first (hash stamp), down to 7/8 of the budget. Their vertices and triangles stay in the
//    heaps (page_out_blocks says why).
//  - In, before a frame (and before tracking draws the model at a predicted pose: pageInView): every paged block the
//    camera may reach. A frame fuses into the blocks within the truncation band of its pixels' depths (the touched
//    blocks); the mesh passes re-mesh the cubes of their neighbours too (the dirty blocks), and those read the
//    corners of their own neighbours: two blocks around the touched ones must be resident, as they are in the run
//    that never pages. A block comes back at whatever pool index the free list hands out.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <string>
#include <tuple>

#include "core/tsdf_corner.h"
#include "gpu/gpu_volume.h"

namespace vkmesh::gpu {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// How far beyond the frustum (in block sides, added to the block's own half diagonal) a block may be and still be
// read by a frame: the dirty blocks' neighbours, two blocks from a touched one on each axis, 2 sqrt(3) ~ 3.46 sides
// on the diagonal. Measured on the noisy room (tests/gpu/test_paging.cpp): with 2 sides, meshing differed from the
// unpaged run's within 3 frames (a corner's refined sign decided with a neighbour block missing); with 3.5, never.
constexpr float kReachMarginBlocks = 3.5f;

}  // namespace

ViewReach GpuVolume::reachOf(const Pose& cameraToWorld, const Intrinsics& intrinsics) const {
    const VolumeParams& p = config_.params;
    const float blockSide = p.voxelSize * float(BLOCK_SIDE);
    return ViewReach(cameraToWorld, intrinsics, p.minDepth, p.maxDepth + p.truncation(), blockSide, kReachMarginBlocks * blockSide);
}

uint32_t GpuVolume::pageInView(const Pose& cameraToWorld, const Intrinsics& intrinsics) {
    if (inFlight_) throw Error("pageInView: a frame is in flight (finishFrame first)");
    if (!paging()) return 0;
    const uint32_t before = pagingSinceFrame_.blocksIn;
    FrameReport growth;   // a pool grown for them is reported with the next frame
    pageIn(cameraToWorld, intrinsics, growth);
    pendingGrowth_.insert(pendingGrowth_.end(), growth.growth.begin(), growth.growth.end());
    return pagingSinceFrame_.blocksIn - before;
}

void GpuVolume::pageIn(const Pose& cameraToWorld, const Intrinsics& intrinsics, FrameReport& frame) {
    if (paged_.empty()) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<PagedBlock> in = paged_.takeReached(reachOf(cameraToWorld, intrinsics));
    if (in.empty()) return;
    const uint32_t n = uint32_t(in.size());
    Counters k = counters_.read();
    if (k.freeTop < n) {
        growBlockPool(config_.blockCapacity + (n - k.freeTop) + config_.blockCapacity / 4, frame);
        k = counters_.read();
        if (k.freeTop < n) {
            for (PagedBlock& b : in) paged_.put(std::move(b));
            throw Error("paging: " + std::to_string(n) + " blocks must come back for the next frame but the block pool (" +
                        std::to_string(config_.blockCapacity) + " blocks) cannot grow to hold them");
        }
    }
    // The top n entries of the free list, popped in the order allocation pops them.
    std::vector<uint32_t> blocks(n);
    vk::downloadFromBuffer(context_, store_.freeList(), blocks.data(), VkDeviceSize(n) * 4, VkDeviceSize(k.freeTop - n) * 4);
    std::reverse(blocks.begin(), blocks.end());
    paging_->reserve(n);
    uint32_t* records = paging_->hostRecords();
    for (uint32_t i = 0; i < n; ++i) std::memcpy(records + size_t(i) * PAGE_RECORD_WORDS, in[i].record.data(), PAGE_RECORD_WORDS * 4);
    lists_.uploadBlockList(blocks);
    const uint32_t listed = k.liveBlockCount;   // the last collected block list's length, which the passes' dispatches read
    counters_.update([&](Counters& c) {
        c.liveBlockCount = n;
        c.rehashLost = 0;
    });
    VkCommandBuffer cmd = beginSubmission();
    paging_->recordIn(cmd, lastPush_, n, hash_, config_.blockCapacity);
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    const uint32_t lost = counters_.read().rehashLost;
    counters_.update([&](Counters& c) {
        c.freeTop -= n;
        c.blocksInUse += n;
        c.hashEntries += n - lost;
        c.liveBlockCount = listed;
        c.rehashLost = 0;
    });
    if (lost)
        throw Error("paging: " + std::to_string(lost) + " blocks coming back found no hash slot within " + std::to_string(HASH_MAX_PROBES) +
                    " probes of a table of " + std::to_string(config_.hashCapacity) + " slots");
    pagingSinceFrame_.blocksIn += n;
    pagingSinceFrame_.bytesIn += uint64_t(n) * PAGE_RECORD_WORDS * 4;
    pagingSinceFrame_.milliseconds += msSince(t0);
}

void GpuVolume::pageOutToBudget(const Pose& cameraToWorld, const Intrinsics& intrinsics, FrameReport& frame) {
    const Counters k = counters_.read();
    const uint32_t budget = config_.residentBlocks;
    if (k.blocksInUse <= budget) return;
    // Cubes waiting for a retry are found by a pass over the live blocks: not while there are any.
    if (retryPending_) return;
    const auto t0 = std::chrono::steady_clock::now();
    const ViewReach view = reachOf(cameraToWorld, intrinsics);
    std::vector<BlockHash::Entry> candidates;
    uint32_t inReach = 0;
    for (const BlockHash::Entry& e : hash_.downloadEntries()) {
        if (e.block == NO_BLOCK) continue;
        if (view.reaches(Eigen::Vector3i(e.x, e.y, e.z))) {
            ++inReach;
            continue;
        }
        candidates.push_back(e);
    }
    // Down to 7/8 of the budget, so that a map growing at its edge pages out every few frames, not every frame.
    const uint32_t target = budget - budget / 8;
    const uint32_t want = uint32_t(std::min<size_t>(k.blocksInUse - std::min(target, k.blocksInUse), candidates.size()));
    // Least recently seen first; ties by coordinate, so that every run pages the same blocks.
    std::sort(candidates.begin(), candidates.end(), [](const BlockHash::Entry& a, const BlockHash::Entry& b) {
        return std::tie(a.stamp, a.z, a.y, a.x) < std::tie(b.stamp, b.z, b.y, b.x);
    });
    candidates.resize(want);
    uint32_t out = 0;
    if (want) {
        std::vector<uint32_t> blocks;
        for (const BlockHash::Entry& e : candidates) blocks.push_back(e.block);
        paging_->reserve(want);
        lists_.uploadBlockList(blocks);
        const uint32_t listed = k.liveBlockCount;
        counters_.update([&](Counters& c) {
            c.liveBlockCount = want;
            c.blocksFreed = 0;
        });
        VkCommandBuffer cmd = beginSubmission();
        paging_->recordOut(cmd, lastPush_, want);
        counters_.recordReadback(cmd);
        recorder_.submitAndWait();
        out = counters_.read().blocksFreed;
        const uint32_t* records = paging_->hostRecords();
        for (uint32_t i = 0; i < want; ++i) {
            const uint32_t* r = records + size_t(i) * PAGE_RECORD_WORDS;
            if (r[3] == PAGE_RECORD_KEPT) continue;
            paged_.put({Eigen::Vector3i(int32_t(r[0]), int32_t(r[1]), int32_t(r[2])), std::vector<uint32_t>(r, r + PAGE_RECORD_WORDS)});
        }
        counters_.update([&](Counters& c) {
            c.freeTop += out;
            c.blocksInUse -= out;
            c.hashEntries -= out;
            c.hashTombstones += out;
            c.liveBlockCount = listed;
            c.blocksFreed = 0;
        });
        pagingSinceFrame_.blocksOut += out;
        pagingSinceFrame_.bytesOut += uint64_t(out) * PAGE_RECORD_WORDS * 4;
    }
    pagingSinceFrame_.milliseconds += msSince(t0);
    const uint32_t resident = k.blocksInUse - out;
    if (resident > budget) {
        pagingSinceFrame_.overBudget = resident - budget;
        if (!budgetWarned_)
            frame.warnings.push_back("--resident-blocks " + std::to_string(budget) + " is below what the view needs: " + std::to_string(inReach) +
                                     " blocks within the camera's reach stay resident (" + std::to_string(resident) +
                                     " resident); give at least " + std::to_string(inReach + inReach / 4));
        budgetWarned_ = true;
    }
}

void GpuVolume::finishPagingReport(FrameReport& frame) {
    frame.paging = pagingSinceFrame_;
    frame.paging.blocksPaged = uint32_t(paged_.size());
    frame.paging.bytesPaged = paged_.bytes();
    frame.growth.insert(frame.growth.begin(), pendingGrowth_.begin(), pendingGrowth_.end());
    pagingSinceFrame_ = {};
    pendingGrowth_.clear();
}

std::vector<BlockSnapshot> GpuVolume::pagedBlockSnapshots() const {
    const float metresPerStep = tsdfFixedPoint(config_.params.truncation()).metresPerStep;
    std::vector<BlockSnapshot> out;
    for (const PagedBlock* b : paged_.all()) {
        const uint32_t* r = b->record.data();
        BlockSnapshot snap;
        snap.coord = b->coord;
        snap.index = NO_BLOCK;
        snap.sdfSum.assign(r + PAGE_RECORD_SDF, r + PAGE_RECORD_SDF + VOXELS_PER_BLOCK);
        snap.weight.resize(VOXELS_PER_BLOCK);
        std::memcpy(snap.weight.data(), r + PAGE_RECORD_WEIGHT, VOXELS_PER_BLOCK * 4);
        snap.sdf.resize(VOXELS_PER_BLOCK);
        for (uint32_t v = 0; v < VOXELS_PER_BLOCK; ++v) snap.sdf[v] = tsdfMean(snap.sdfSum[v], snap.weight[v], metresPerStep);
        if (store_.hasColor()) snap.color.assign(r + PAGE_RECORD_COLOR, r + PAGE_RECORD_COLOR + VOXELS_PER_BLOCK);
        out.push_back(std::move(snap));
    }
    return out;
}

void GpuVolume::requireNothingPaged(const char* what) const {
    if (!paged_.empty())
        throw Error(std::string(what) + " reads every block of the map, and " + std::to_string(paged_.size()) +
                    " are paged out (resident blocks " + std::to_string(config_.residentBlocks) + "): not built for a paged map yet");
}

}  // namespace vkmesh::gpu
