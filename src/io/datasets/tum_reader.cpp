// TUM RGB-D and ICL-NUIM (TUM-compatible release): depth.txt (or associations.txt), groundtruth.txt, rgb.txt.
#include "io/datasets/layout_reader.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace vkmesh::datasets {

using namespace io::text;

namespace {

struct Stamped {
    double t;
    size_t line;
    fs::path path;  // depth entries only
    Pose pose;      // groundtruth entries only
};

std::vector<Stamped> stamped(const std::vector<io::TimedPath>& v) {
    std::vector<Stamped> out;
    out.reserve(v.size());
    for (const auto& e : v) out.push_back({e.timestamp, e.line, e.path, Pose::Identity()});
    return out;
}

std::vector<Stamped> readDepthList(const fs::path& folder, const fs::path& file) {
    std::ifstream in = openText(file);
    return stamped(io::parseDepthList(in, file.string(), folder));
}

std::vector<Stamped> readAssociations(const fs::path& folder, const fs::path& file) {
    std::ifstream in = openText(file);
    return stamped(io::parseAssociations(in, file.string(), folder));
}

std::vector<Stamped> readGroundtruth(const fs::path& file) {
    std::ifstream in = openText(file);
    std::vector<Stamped> out;
    for (auto& p : io::parseTrajectory(in, file.string())) out.push_back({p.timestamp, p.line, {}, p.cameraToWorld});
    return out;
}

// Sorts by time (unsorted files are legitimate) and drops repeated timestamps, keeping the entry that
// came first in the file. Returns how many were dropped.
size_t sortAndDedupe(std::vector<Stamped>& v, const fs::path& file, std::vector<std::string>& warnings) {
    std::stable_sort(v.begin(), v.end(), [](const Stamped& a, const Stamped& b) { return a.t < b.t; });
    std::vector<Stamped> kept;
    kept.reserve(v.size());
    size_t dropped = 0;
    for (auto& s : v) {
        if (!kept.empty() && kept.back().t == s.t) {
            if (dropped < kMaxFrameWarnings)
                warnings.push_back(at(file, s.line) + ": timestamp " + fmtTime(s.t) + " repeats line " +
                                   std::to_string(kept.back().line) + "; kept the first");
            ++dropped;
            continue;
        }
        kept.push_back(std::move(s));
    }
    v = std::move(kept);
    return dropped;
}

// ICL-NUIM's TUM-compatible files use frame indices as timestamps; TUM uses Unix time (~1.3e9 s).
bool timestampsAreFrameIndices(const std::vector<Stamped>& depth) {
    if (depth.empty()) return false;
    for (const auto& s : depth)
        if (s.t < 0 || s.t >= 1e6 || s.t != std::floor(s.t)) return false;
    return true;
}

// The entry of `sorted` (by time) nearest to time t, and how far it is; nothing when `sorted` is empty.
struct Nearest {
    const Stamped* entry;
    double distance;
};
std::optional<Nearest> nearestInTime(const std::vector<Stamped>& sorted, double t) {
    auto it = std::lower_bound(sorted.begin(), sorted.end(), t, [](const Stamped& s, double time) { return s.t < time; });
    const Stamped* best = it != sorted.end() ? &*it : nullptr;
    if (it != sorted.begin() && (!best || t - std::prev(it)->t < best->t - t)) best = &*std::prev(it);
    if (!best) return std::nullopt;
    return Nearest{best, std::abs(best->t - t)};
}

}  // namespace

Layout readTum(const fs::path& folder, const std::string& folderName, bool requirePoses) {
    Layout layout;
    fs::path depthFile = folder / "depth.txt";
    fs::path gtFile = folder / "groundtruth.txt";
    std::error_code ec;
    // depth.txt is authoritative; associations.txt is a derived file, used only when it is all there is.
    fs::path listFile = fs::is_regular_file(depthFile, ec) ? depthFile : folder / "associations.txt";
    const bool hasGroundtruth = fs::is_regular_file(gtFile, ec);
    if (!hasGroundtruth && requirePoses)
        throw Error("TUM/ICL-NUIM layout in " + folder.string() + ": found " + listFile.filename().string() +
                    " but no groundtruth.txt with the camera poses (" + kTrackingHint + ")");

    std::vector<Stamped> depth = listFile == depthFile ? readDepthList(folder, listFile) : readAssociations(folder, listFile);
    if (depth.empty()) throw Error(listFile.string() + " lists no depth frames");
    std::vector<Stamped> gt;
    if (hasGroundtruth) {
        gt = readGroundtruth(gtFile);
        if (gt.empty() && requirePoses) throw Error(gtFile.string() + " has no poses (" + kTrackingHint + ")");
    }

    const size_t listed = depth.size();
    layout.skipped = sortAndDedupe(depth, listFile, layout.warnings);
    sortAndDedupe(gt, gtFile, layout.warnings);

    auto namesSensor = [&](int sensor) {
        std::string n = std::to_string(sensor);
        return containsWord(folderName, "freiburg" + n) || containsWord(folderName, "fr" + n);
    };
    const int tumSensor = namesSensor(1) ? 1 : namesSensor(2) ? 2 : namesSensor(3) ? 3 : 0;
    // The folder name is the primary clue (the shared copy is "iclnuim_office_traj0"); frame-index
    // timestamps catch ICL-NUIM folders renamed after their scene ("living_room_traj0_frei_png"), unless
    // the name says which TUM sensor recorded the sequence.
    bool icl = containsWord(folderName, "icl") || (tumSensor == 0 && timestampsAreFrameIndices(depth));
    layout.kind = icl ? DatasetKind::ICLNUIM : DatasetKind::TUM;
    // The default calibration is a preset in data/cameras/ (ICL-NUIM's fy is negative: its poses are for a
    // camera whose image y axis points up).
    if (icl) {
        layout.preset = "icl_nuim";
    } else if (tumSensor != 0) {
        layout.preset = "tum_fr" + std::to_string(tumSensor);
    } else {
        layout.preset = "tum_default";
        // Dataset::open appends the preset's values.
        layout.intrinsicsWarning = "folder name '" + folderName +
                                   "' names no TUM sensor (freiburg1/2/3 or fr1/2/3); using the default intrinsics";
    }

    // TUM's motion capture runs at ~100 Hz, so a pose within 20 ms exists unless tracking dropped out;
    // ICL-NUIM's timestamps are frame indices and must match exactly.
    const double tolerance = icl ? 0.5 : 0.020;
    const std::string tolText = icl ? "the same frame index" : "20 ms";
    auto isNear = [&](double dt) { return icl ? dt < tolerance : dt <= tolerance; };  // strict for ICL: 0.5 would be a tie
    auto describeDistance = [&](double dt) { return icl ? fmt(dt) + " frames" : fmtFixed(dt * 1000.0, 1) + " ms"; };
    for (const auto& d : depth) {
        const std::optional<Nearest> pose = nearestInTime(gt, d.t);
        FrameInfo f;
        f.timestamp = d.t;
        f.depthPath = d.path;
        if (pose && isNear(pose->distance)) {
            f.cameraToWorld = pose->entry->pose;
            f.hasPose = true;
        } else if (requirePoses) {  // gt is not empty here
            warnSkipped(layout, at(listFile, d.line) + ": depth frame " + fmtTime(d.t) + " (" + d.path.filename().string() +
                                    ") has no pose within " + tolText + " in groundtruth.txt (nearest is " +
                                    describeDistance(pose->distance) + " away); skipped");
            continue;
        }
        layout.frames.push_back(std::move(f));
    }
    if (layout.frames.empty())
        throw Error("none of the " + std::to_string(depth.size()) + " depth frames in " + listFile.string() +
                    " (timestamps " + fmtTime(depth.front().t) + " .. " + fmtTime(depth.back().t) + ") has a pose within " +
                    tolText + " in " + gtFile.string() + " (timestamps " + fmtTime(gt.front().t) + " .. " +
                    fmtTime(gt.back().t) + ")");
    summariseSkipped(layout, listed, requirePoses ? "no pose within " + tolText + ", or a repeated timestamp" : "a repeated timestamp");
    if (hasGroundtruth) summariseFramesWithoutPose(layout, "no pose within " + tolText + " in " + gtFile.filename().string());

    // Colour: rgb.txt, the image nearest in time to each depth frame (the sensor streams are not
    // synchronised in TUM; ICL-NUIM's share the frame index). Colour is optional: a broken rgb.txt costs
    // the colour, not the reconstruction.
    const fs::path rgbFile = folder / "rgb.txt";
    if (fs::is_regular_file(rgbFile, ec)) {
        std::vector<Stamped> rgb;
        try {
            rgb = readDepthList(folder, rgbFile);
        } catch (const Error& e) {
            layout.warnings.push_back(std::string(e.what()) + "; colour ignored");
        }
        sortAndDedupe(rgb, rgbFile, layout.warnings);
        for (FrameInfo& f : layout.frames) {
            const std::optional<Nearest> color = nearestInTime(rgb, f.timestamp);
            if (!color) break;
            if (isNear(color->distance)) {
                f.colorPath = color->entry->path;
            } else {
                warnNoColor(layout, rgbFile.string() + ": no colour image within " + tolText + " of depth frame " +
                                        fmtTime(f.timestamp) + " (" + f.depthPath.filename().string() + "; nearest is " +
                                        describeDistance(color->distance) + " away); that frame has no colour");
            }
        }
    }
    return layout;
}

}  // namespace vkmesh::datasets
