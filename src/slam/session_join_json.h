// `vkmesh merge --register --stats` and vkmesh.merge_maps(register=True): how each later session was registered to
// the first ("registration" beside mergeReportJson's keys; docs/SCALING.md lists them). nlohmann::json is a build
// dependency of the library's .cpp only: this header is for front ends that link it (as api/run_stats_json.h).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

#include "slam/session_join.h"

namespace vkmesh::slam {

// {"sessions": [one per later map: the map, the first map, transform (row-major 4 x 4), moved_m, turned_degrees,
// keyframes, pairs registered / verified / agreeing, the spread of the agreeing ones, every pair tried, ms],
// "frames_moved", "move_ms"}.
nlohmann::json joinReportJson(const JoinReport& report, const std::vector<std::filesystem::path>& inputs);

}  // namespace vkmesh::slam
