// Map algebra on the host (docs/SCALING.md): the sum of saved maps. A TSDF corner is an integer sum of distance
// steps and a count of observations (shared_layout.h, "A TSDF corner"), independent of the order of the frames,
// so the map of frames fused in several runs is the sum of the runs' maps, exactly: sums and counts added
// corner by corner, blocks united. Colour (an average) is combined by its weights, to within a quarter level.
//
// The result holds no mesh (every cube empty, every edge without a vertex): the mesh follows from the TSDF, and
// a GPU volume builds it (GpuVolume::rebuildMesh; api/map_merge.h does all of it). Colour is weighted by the
// corner's count, as fusion weighs it: where some observations brought no colour (frames without a colour image),
// merging in steps may give another colour than merging at once. Everything that can refuse
// a merge is checked here, before a device is opened or a file written.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/map_format.h"

namespace vkmesh::map {

// A setting two maps disagree on: what it is, the option that sets it, and both values.
struct SettingDifference {
    std::string what, option;
    double a = 0, b = 0;
};

// How strictly allocation by tiles is compared: as on/off (a map continued by a run: the run follows the
// map's rules), or with the rule set too (two maps merged: de-integrating either's frames later must repeat
// the allocation they were fused with).
enum class AllocationRules { OnOrOff, Exact };

// The settings that change what a frame computes (the Map-kind settings, api/settings.cpp), where a and b differ.
// Depth range, image size, vertex-update path, lock-free claims and growth are the caller's: they give the same map.
std::vector<SettingDifference> settingDifferences(const Settings& a, const Settings& b, AllocationRules rules);

struct MergeInput {
    std::string name;       // for error messages (the file)
    const MapData* map = nullptr;
};

struct MergeSummary {
    size_t blocks = 0;        // in the result
    size_t sharedBlocks = 0;  // coordinates held by more than one input
    uint64_t corners = 0;     // observed corners (count > 0) in the result
};

// The sum of the inputs (at least one). Throws vkmesh::Error naming the input and the reason when:
// - the settings differ (naming the setting, its option and both values),
// - a map is bounded (--keep-radius, --recycle: it forgot what it fused), uses colour mode recent (no weights
//   to combine it by) or was fused with --mode baseline (no incremental mesh to rebuild),
// - a corner would hold more than SDF_MAX_COUNT observations (naming the block and the counts),
// - an input is inconsistent (a count that is not a whole number, a sum beyond what its count allows),
// - a map holds a per-block section this build cannot add, or one the others lack.
// The result's blocks are in coordinate order with pool indices 0..N-1, and it is the same whatever the order of
// the inputs (settings that are not compared come from the input with the most frame numbers); merged in steps,
// (A + B) + C and A + (B + C) hold the same TSDF and colours within a quarter level where every observation had
// a colour. Its counters are those of a map with no mesh; frame numbers add up; capacities are the largest of the
// inputs' (blocks and hash slots at least what the union needs).
//
// `keep`, when given, restricts the result to the blocks (by block coordinate) it accepts: a part of the sum, to
// mesh one tile of it with its neighbours (api/map_merge.h) without the rest.
// (BlockFilter: core/map_format.h.)
MapData merge(const std::vector<MergeInput>& inputs, MergeSummary* summary = nullptr, const BlockFilter& keep = {});

}  // namespace vkmesh::map
