#include "core/map_merge.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <tuple>

#include "core/types.h"
#include "core/voxel_color.h"

namespace vkmesh::map {

namespace {

using namespace gpu;

std::string number(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// The per-corner arrays this build knows how to add: the TSDF's (summed, counted, weighted) and the mesh's
// (left empty for the rebuild). A map holding any other cannot be merged without losing it.
const uint32_t kSums = tag("sdf_"), kCounts = tag("wght"), kColors = tag("colr");
const uint32_t kCubes = tag("cube"), kEdges[3] = {tag("edgx"), tag("edgy"), tag("edgz")};

bool isMeshArray(uint32_t t) { return t == kCubes || t == kEdges[0] || t == kEdges[1] || t == kEdges[2]; }

uint32_t powerOfTwoAtLeast(uint64_t v) {
    uint64_t p = 1;
    while (p < v) p <<= 1;
    return uint32_t(std::min<uint64_t>(p, uint64_t(1) << 31));
}

std::string blockName(const Block& b) {
    return "block (" + std::to_string(b.x) + ", " + std::to_string(b.y) + ", " + std::to_string(b.z) + ")";
}

// Refuses what cannot be added: a bounded map, colour without weights, a baseline map, a corner that is not
// an exact sum and count.
void checkMergeable(const MergeInput& in) {
    const MapData& m = *in.map;
    const Settings& s = m.settings;
    if (s.keepRadius > 0 || s.recycle)
        throw Error(in.name + ": a bounded map (--keep-radius or --recycle) forgot part of what it fused, so its sum with another map is "
                              "not the map of their frames; merge maps fused without them");
    if (s.colorMode == COLOR_MODE_RECENT)
        throw Error(in.name + ": colour mode recent keeps no weights to combine colours by; merge maps fused with --color-mode average "
                              "(or --no-color)");
    if (!s.incrementalMesh)
        throw Error(in.name + ": fused with --mode baseline; merging builds the incremental mesh (fuse with --mode incremental)");
    const CornerArray* sums = m.corners(kSums);
    const CornerArray* counts = m.corners(kCounts);
    if (!sums || !counts) throw Error(in.name + ": the map has no TSDF sections ('sdf_', 'wght')");
    for (const CornerArray& a : m.cornerArrays)
        if (a.tag != kSums && a.tag != kCounts && a.tag != kColors && !isMeshArray(a.tag))
            throw Error(in.name + ": the map holds a per-block section '" + tagName(a.tag) + "' that merging cannot add");
    for (size_t i = 0; i < counts->words.size(); ++i) {
        const float w = std::bit_cast<float>(counts->words[i]);
        const int64_t sum = int32_t(sums->words[i]);
        if (!(w >= 0 && w <= float(SDF_MAX_COUNT) && w == std::floor(w)) ||
            std::abs(sum) > int64_t(SDF_STEPS_PER_TRUNCATION) * int64_t(w))
            throw Error(in.name + ": " + blockName(m.blocks[i / VOXELS_PER_BLOCK]) + ", corner " + std::to_string(i % VOXELS_PER_BLOCK) +
                        " holds a sum of " + std::to_string(sum) + " steps over a count of " + number(w) +
                        ", which no fusion gives (a map of an older build or a damaged file)");
    }
}

}  // namespace

std::vector<SettingDifference> settingDifferences(const Settings& a, const Settings& b, AllocationRules rules) {
    const bool exact = rules == AllocationRules::Exact;
    const SettingDifference all[] = {
        {"voxel size", "--voxel", a.voxelSize, b.voxelSize},
        {"truncation (voxels)", "--trunc", a.truncVoxels, b.truncVoxels},
        {"max weight", "--max-weight", a.maxWeight, b.maxWeight},
        {"min mesh weight", "--min-weight", a.minMeshWeight, b.minMeshWeight},
        {"allocation stride", "--alloc-stride", double(a.allocationStride), double(b.allocationStride)},
        {exact ? "allocation (0 pixel by pixel, 1 or 2 by tiles with those rules)" : "allocation by tiles (1) or pixel by pixel (0)",
         "--alloc-tiles, --alloc-pixels", exact ? double(a.allocationTiles) : double(a.allocationTiles != 0),
         exact ? double(b.allocationTiles) : double(b.allocationTiles != 0)},
        {"mesh mode (1 = incremental)", "--mode", double(a.incrementalMesh != 0), double(b.incrementalMesh != 0)},
        {"refinement", "--refine", double(a.refine != 0), double(b.refine != 0)},
        {"refinement epsilon", "--refine-eps", a.refine ? a.refineEpsilonVoxels : 0.0, a.refine ? b.refineEpsilonVoxels : 0.0},
        {"keep radius", "--keep-radius", a.keepRadius, b.keepRadius},
        {"recycling", "--recycle", double(a.recycle != 0), double(b.recycle != 0)},
        {"recycle after (frames)", "--recycle-after", a.recycle ? a.recycleAfterFrames : 0.0, a.recycle ? b.recycleAfterFrames : 0.0},
        {"starve weight", "--starve-weight", a.recycle ? a.starveWeight : 0.0, a.recycle ? b.starveWeight : 0.0},
        {"colour fusion (0 off, 1 average, 2 recent)", "--no-color, --color-mode", double(a.colorMode), double(b.colorMode)},
        {"colour recency", "--color-recency", a.colorMode == COLOR_MODE_RECENT ? a.colorRecency : 0.0,
         a.colorMode == COLOR_MODE_RECENT ? b.colorRecency : 0.0},
    };
    std::vector<SettingDifference> out;
    for (const SettingDifference& d : all)
        if (d.a != d.b) out.push_back(d);
    return out;
}

MapData merge(const std::vector<MergeInput>& inputs, MergeSummary* summary, const BlockFilter& keep) {
    if (inputs.empty()) throw Error("merge: no maps given");
    const MapData& first = *inputs[0].map;
    for (const MergeInput& in : inputs) checkMergeable(in);
    for (size_t i = 1; i < inputs.size(); ++i) {
        const MapData& m = *inputs[i].map;
        const std::vector<SettingDifference> d = settingDifferences(first.settings, m.settings, AllocationRules::Exact);
        if (!d.empty())
            throw Error(inputs[i].name + ": fused with " + d[0].what + " " + number(d[0].b) + " but " + inputs[0].name + " with " +
                        number(d[0].a) + " (" + d[0].option + "); only maps fused with the same settings add up" +
                        (d.size() > 1 ? " (" + std::to_string(d.size() - 1) + " more settings differ)" : ""));
        // Frames kept beside the merged map are re-fused (corrected) with one depth range.
        if (m.settings.minDepth != first.settings.minDepth || m.settings.maxDepth != first.settings.maxDepth)
            throw Error(inputs[i].name + ": fused with depths " + number(m.settings.minDepth) + " to " + number(m.settings.maxDepth) + " m but " +
                        inputs[0].name + " with " + number(first.settings.minDepth) + " to " + number(first.settings.maxDepth) +
                        " m (--max-depth); only maps fused with the same settings add up");
        if (m.features != first.features)
            throw Error(inputs[i].name + ": holds other sections than " + inputs[0].name + " (feature flags " + std::to_string(m.features) +
                        " against " + std::to_string(first.features) + ")");
    }
    // Every input holds the same per-block sections (a map with colour but no colour section passes the parser).
    const bool color = first.settings.colorMode != 0;
    for (const MergeInput& in : inputs) {
        for (const CornerArray& a : first.cornerArrays)
            if (!in.map->corners(a.tag)) throw Error(in.name + ": the map has no section '" + tagName(a.tag) + "', which " + inputs[0].name + " has");
        for (const CornerArray& a : in.map->cornerArrays)
            if (!first.corners(a.tag)) throw Error(in.name + ": the map has a section '" + tagName(a.tag) + "', which " + inputs[0].name + " has not");
        if (color && !in.map->corners(kColors)) throw Error(in.name + ": a map with colour has no colour section ('colr')");
    }
    // The input whose frame header, caller settings (lock-free claims, growth, ...) and settings that are off (the
    // recency of an average colour) the result keeps: the one with the most frame numbers, ties broken by the bytes,
    // so that the order of the inputs does not matter.
    auto later = [](const MapData& a, const MapData& b) {
        if (a.frameNumber != b.frameNumber) return a.frameNumber > b.frameNumber;
        if (const int c = std::memcmp(&a.lastPush, &b.lastPush, sizeof(FramePush))) return c > 0;
        return std::memcmp(&a.settings, &b.settings, sizeof(Settings)) > 0;
    };
    const MapData* latest = &first;
    for (const MergeInput& in : inputs)
        if (later(*in.map, *latest)) latest = in.map;

    // The union of the blocks, in coordinate order (z, y, x): the same result whatever the order of the inputs.
    struct Part {
        size_t input, block;
    };
    std::map<std::tuple<int32_t, int32_t, int32_t>, std::vector<Part>> blocks;
    for (size_t i = 0; i < inputs.size(); ++i) {
        const MapData& m = *inputs[i].map;
        for (size_t b = 0; b < m.blocks.size(); ++b)
            if (!keep || keep(m.blocks[b].x, m.blocks[b].y, m.blocks[b].z)) blocks[{m.blocks[b].z, m.blocks[b].y, m.blocks[b].x}].push_back({i, b});
    }
    const size_t n = blocks.size();
    if (n > SIZE_MAX / VOXELS_PER_BLOCK || n >= (size_t(1) << 31)) throw Error("merge: " + std::to_string(n) + " blocks are too many for one map");

    MapData out;
    out.features = first.features;
    out.settings = latest->settings;
    // Arrays in the first input's order (components list theirs); the mesh's empty.
    for (const CornerArray& a : first.cornerArrays) {
        CornerArray c{a.tag, std::vector<uint32_t>(n * VOXELS_PER_BLOCK, 0)};
        if (a.tag != kCubes && isMeshArray(a.tag)) std::fill(c.words.begin(), c.words.end(), EMPTY_SLOT);
        out.cornerArrays.push_back(std::move(c));
    }
    auto arrayOf = [&](uint32_t t) -> std::vector<uint32_t>* {
        for (CornerArray& a : out.cornerArrays)
            if (a.tag == t) return &a.words;
        return nullptr;
    };
    std::vector<uint32_t>& sums = *arrayOf(kSums);
    std::vector<uint32_t>& counts = *arrayOf(kCounts);
    std::vector<uint32_t>* colors = color ? arrayOf(kColors) : nullptr;

    MergeSummary s;
    out.blocks.reserve(n);
    size_t index = 0;
    for (const auto& [key, parts] : blocks) {
        Block merged{std::get<2>(key), std::get<1>(key), std::get<0>(key), uint32_t(index), 0, {}};
        if (parts.size() > 1) ++s.sharedBlocks;
        for (uint32_t c = 0; c < VOXELS_PER_BLOCK; ++c) {
            const size_t at = index * VOXELS_PER_BLOCK + c;
            int64_t sum = 0;
            uint64_t count = 0, colorWeight = 0;
            uint64_t channels[3] = {0, 0, 0};
            uint32_t unweightedColor = 0;   // a colour on a corner whose count was taken back to 0: kept if nothing else has one
            for (const Part& p : parts) {
                const MapData& m = *inputs[p.input].map;
                const size_t from = p.block * VOXELS_PER_BLOCK + c;
                const uint32_t w = uint32_t(std::bit_cast<float>(m.corners(kCounts)->words[from]));   // whole: checkMergeable
                sum += int32_t(m.corners(kSums)->words[from]);
                count += w;
                if (!color) continue;
                const uint32_t word = m.corners(kColors)->words[from];
                if (!hasVoxelColor(word)) continue;
                if (w == 0) {
                    unweightedColor = std::max(unweightedColor, word);
                    continue;
                }
                const ColorChannels ch = unpackVoxelColor(word);
                for (int k = 0; k < 3; ++k) channels[k] += uint64_t(ch[k]) * w;
                colorWeight += w;
            }
            if (count > SDF_MAX_COUNT) {
                std::string counts;
                for (const Part& p : parts)
                    counts += (counts.empty() ? "" : ", ") + inputs[p.input].name + " " +
                              number(std::bit_cast<float>(inputs[p.input].map->corners(kCounts)->words[p.block * VOXELS_PER_BLOCK + c]));
                throw Error("merge: " + blockName(merged) + ", corner " + std::to_string(c) + " would hold " + std::to_string(count) +
                            " observations (" + counts + "), more than a corner can count (" + std::to_string(SDF_MAX_COUNT) +
                            "); merge fewer maps into one");
            }
            sums[at] = uint32_t(int32_t(sum));   // |sum| <= 4096 * count < 2^31
            counts[at] = std::bit_cast<uint32_t>(float(count));
            if (count) ++s.corners;
            if (!colors) continue;
            if (colorWeight) {
                // The weighted mean, rounded to the nearest quarter level: symmetric in the inputs.
                uint32_t q[3];
                for (int k = 0; k < 3; ++k) q[k] = uint32_t((channels[k] + colorWeight / 2) / colorWeight);
                (*colors)[at] = packVoxelColor(q[0], q[1], q[2]);
            } else {
                (*colors)[at] = unweightedColor;
            }
        }
        for (const Part& p : parts) merged.hashStamp = std::max(merged.hashStamp, inputs[p.input].map->blocks[p.block].hashStamp);
        out.blocks.push_back(merged);
        ++index;
    }

    // Frame numbers add up (every input's frames are in the sum).
    for (const MergeInput& in : inputs) {
        const MapData& m = *in.map;
        out.frameNumber += m.frameNumber;
        out.framesIntegrated += m.framesIntegrated;
        out.settings.imageWidth = std::max(out.settings.imageWidth, m.settings.imageWidth);
        out.settings.imageHeight = std::max(out.settings.imageHeight, m.settings.imageHeight);
        Capacities& k = out.capacities;
        const Capacities& mk = m.capacities;
        k = {std::max(k.blocks, mk.blocks),   std::max(k.hashSlots, mk.hashSlots), std::max(k.touched, mk.touched),
             std::max(k.retype, mk.retype),   std::max(k.vertices, mk.vertices),   std::max(k.chunks, mk.chunks)};
    }
    out.lastPush = latest->lastPush;
    out.lastPush.frameNumber = out.frameNumber;
    out.capacities.blocks = std::max(out.capacities.blocks, uint32_t(n));
    out.capacities.hashSlots = std::max(out.capacities.hashSlots, powerOfTwoAtLeast(2 * uint64_t(n)));
    out.retryPending = 0;
    // Counters of a map with no mesh: only the pool's and the hash's counts.
    out.counters = Counters{};
    out.counters.blocksInUse = out.counters.liveBlockCount = out.counters.hashEntries = uint32_t(n);
    out.blockFree = {uint32_t(n), {}};
    out.vertexFree = {0, {}};
    out.chunkFree = {0, {}};
    s.blocks = n;
    if (summary) *summary = s;
    return out;
}

}  // namespace vkmesh::map
