#include "slam/session_join_json.h"

#include "core/icp_solve.h"

namespace vkmesh::slam {

nlohmann::json joinReportJson(const JoinReport& report, const std::vector<std::filesystem::path>& inputs) {
    nlohmann::json sessions = nlohmann::json::array();
    for (size_t i = 0; i < report.registrations.size(); ++i) {
        const SessionRegistration& r = report.registrations[i];
        std::vector<double> transform;
        for (int row = 0; row < 4; ++row)
            for (int col = 0; col < 4; ++col) transform.push_back(r.secondToFirst(row, col));
        nlohmann::json pairs = nlohmann::json::array();
        for (const SessionMatch& m : r.matches)
            pairs.push_back({{"frame", m.secondFrame}, {"first_frame", m.firstFrame}, {"dissimilarity", m.dissimilarity},
                             {"verified", m.verified}, {"agrees", m.agrees}, {"rmse_m", m.rmse}, {"reason", m.failure}});
        sessions.push_back({{"map", i + 1 < inputs.size() ? inputs[i + 1].string() : std::string()},
                            {"to", inputs.empty() ? std::string() : inputs[0].string()},
                            {"transform", transform},
                            {"moved_m", translationMetres(r.secondToFirst)},
                            {"turned_degrees", rotationDegrees(r.secondToFirst)},
                            {"keyframes", {{"first", r.firstKeyframes}, {"second", r.secondKeyframes}, {"second_tried", r.secondKeyframesTried}}},
                            {"pairs_registered", r.registrations},
                            {"pairs_verified", r.verified},
                            {"pairs_agreeing", r.agreeing},
                            {"spread_m", r.spreadMetres},
                            {"spread_degrees", r.spreadDegrees},
                            {"pairs", pairs},
                            {"ms", r.milliseconds}});
    }
    return {{"sessions", sessions}, {"frames_moved", report.framesMoved}, {"move_ms", report.moveMs}};
}

}  // namespace vkmesh::slam
