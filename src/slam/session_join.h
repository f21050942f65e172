// `vkmesh merge --register`: saved maps of one place from separate sessions (each in the world frame of its own
// first pose) joined into one map (docs/SCALING.md, "Sessions of one place").
//
//   JoinReport r = joinSessions({"monday.vkmap", "tuesday.vkmap"}, "both.vkmap", JoinOptions{});
//
// Each later map is registered to the first by the frames their stores keep (slam/session_registration.h); its
// frames are then re-fused at their poses in the first map's frame (the exact correction, docs/CORRECTION.md: the
// moved map equals one fused at those poses from the start) and the maps are added (api/map_merge.h): the result is
// the map of every session's frames at the registered poses. Every map needs its frame store: without its frames a
// map can neither be recognised nor moved exactly. Errors name the map and the reason, and nothing is written.
#pragma once

#include <filesystem>
#include <vector>

#include "api/map_merge.h"
#include "slam/session_registration.h"
#include "vk/context.h"

namespace vkmesh::slam {

struct JoinOptions {
    SessionRegistrationOptions registration;
    MergeOptions merge;   // the device, the merged frame store's budget, the mesh, tiles (as vkmesh merge)
};

struct JoinReport {
    std::vector<SessionRegistration> registrations;   // of maps 2, 3, ... to the first
    size_t framesMoved = 0;                           // the later maps' frames re-fused in the first map's frame
    double moveMs = 0;
    MergeReport merge;
};

JoinReport joinSessions(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const JoinOptions& options);
// The same on the caller's device (options.merge.device is not used).
JoinReport joinSessions(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                        const JoinOptions& options);

}  // namespace vkmesh::slam
