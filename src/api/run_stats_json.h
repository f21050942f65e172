// A run's statistics as JSON: the keys of `vkmesh fuse --stats` that the library knows (docs/RESULTS.md and users'
// scripts read them: keys are added, never renamed or dropped). The CLI adds what only it knows (the dataset, the
// mesh file and its analyses, map and viewer timings); Python returns the same document as a dict.
// nlohmann::json is a build dependency of the library's .cpp only: this header is for front ends that link it.
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "api/map_merge.h"
#include "api/mapper.h"

namespace vkmesh {

// {"median", "mean", "max"} of a series (nulls when empty): how --stats writes every per-frame series.
nlohmann::json seriesJson(const std::vector<double>& values);

// Everything the Mapper knows: settings, frames, per-frame times and counts, capacities and their events, memory,
// tracking, loop closure, warnings. Before the first frame (no volume) only the settings.
nlohmann::json runStatsJson(const Mapper& mapper);

// `vkmesh merge --stats` and vkmesh.merge_maps(): the inputs, what the sum holds, its mesh, where the time went.
nlohmann::json mergeReportJson(const MergeReport& report);

}  // namespace vkmesh
