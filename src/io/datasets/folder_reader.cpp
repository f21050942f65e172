// A plain folder of depth (+ colour) images with a camera.json and no poses: what a RealSense recording, a
// phone scan or another tool's export looks like once its depth is written as 16-bit PNGs. Opened only for
// camera tracking, which estimates the poses.
#include "io/datasets/layout_reader.h"

#include <cmath>
#include <map>

namespace vkmesh::datasets {

using namespace io::text;

namespace {

// The number a file name carries: the whole stem when it is one ("000123", or Unix time such as
// "1305031102.175304", which then stays in seconds), else its last run of digits ("depth_000123" -> 123).
std::optional<double> numberInName(const std::string& stem) {
    double whole;
    if (parseNumber(stem, whole) && std::isfinite(whole)) return whole;
    const size_t end = stem.find_last_of("0123456789");
    if (end == std::string::npos) return std::nullopt;
    const size_t before = stem.find_last_not_of("0123456789", end);
    const size_t begin = before == std::string::npos ? 0 : before + 1;
    long long n;
    if (!parseInteger(std::string_view(stem).substr(begin, end + 1 - begin), n)) return std::nullopt;  // too long
    return static_cast<double>(n);
}

// Timestamps from the names when every name has a number and they increase in name order (so that the
// trajectory written for the frames is in time order); otherwise each frame's position, with a warning.
void numberFrames(Layout& layout, const fs::path& depthDir) {
    std::vector<double> numbers;
    for (const FrameInfo& f : layout.frames) {
        const std::optional<double> n = numberInName(f.depthPath.stem().string());
        if (!n) {
            layout.warnings.push_back("depth image " + f.depthPath.string() +
                                      " has no number in its name; frames are numbered by their position in " +
                                      depthDir.string() + " instead");
            break;
        }
        if (!numbers.empty() && *n <= numbers.back()) {
            layout.warnings.push_back("the numbers in the names of the depth images in " + depthDir.string() +
                                      " do not increase in name order (" + fmtTime(numbers.back()) + " then " +
                                      fmtTime(*n) + ", in " + f.depthPath.filename().string() +
                                      "); frames are numbered by their position instead");
            break;
        }
        numbers.push_back(*n);
    }
    for (size_t i = 0; i < layout.frames.size(); ++i)
        layout.frames[i].timestamp = numbers.size() == layout.frames.size() ? numbers[i] : static_cast<double>(i);
}

// Colour from color/ or rgb/: the image with the depth image's stem ("000123.png" and "000123.jpg"), else,
// when no stem matches and the counts are equal, the k-th image in name order.
void pairColor(Layout& layout, const fs::path& folder) {
    for (const char* name : {"color", "rgb"}) {
        const fs::path dir = folder / name;
        const std::vector<fs::path> colors = colorImagesIn(dir);
        if (colors.empty()) continue;
        std::map<std::string, fs::path> byStem;
        for (const fs::path& c : colors) byStem.emplace(c.stem().string(), c);  // the first in name order wins
        size_t matched = 0;
        for (const FrameInfo& f : layout.frames) matched += byStem.count(f.depthPath.stem().string());
        if (matched > 0) {
            for (FrameInfo& f : layout.frames) {
                auto it = byStem.find(f.depthPath.stem().string());
                if (it != byStem.end())
                    f.colorPath = it->second;
                else
                    warnNoColor(layout, "depth image " + f.depthPath.string() + " has no colour image of the same name in " +
                                            dir.string() + "; that frame has no colour");
            }
        } else if (colors.size() == layout.frames.size()) {
            for (size_t k = 0; k < colors.size(); ++k) layout.frames[k].colorPath = colors[k];
        } else {
            layout.warnings.push_back(dir.string() + " holds " + std::to_string(colors.size()) + " colour images for " +
                                      std::to_string(layout.frames.size()) +
                                      " depth images, none named like a depth image; colour ignored (name each like "
                                      "its depth image, or give one per depth image)");
        }
        break;
    }
}

}  // namespace

fs::path folderLayoutDepthDir(const fs::path& folder) {
    std::error_code ec;
    return fs::is_directory(folder / "depth", ec) ? folder / "depth" : folder;
}

Layout readFolder(const fs::path& folder, bool requirePoses) {
    if (requirePoses)
        throw Error("folder of depth images with a camera.json in " + folder.string() + ": no poses; " + kTrackingHint);
    Layout layout;
    layout.kind = DatasetKind::Folder;
    // No preset: nothing about a plain folder says which camera took it, so camera.json (or the options)
    // must give every value; Dataset::open says which are missing.
    const fs::path depthDir = folderLayoutDepthDir(folder);
    const std::vector<fs::path> images = filesWithExtension(depthDir, ".png");
    if (images.empty()) throw Error("folder layout: " + depthDir.string() + " holds no .png depth images");
    for (const fs::path& image : images) {
        FrameInfo f;
        f.depthPath = image;
        layout.frames.push_back(std::move(f));
    }
    numberFrames(layout, depthDir);
    pairColor(layout, folder);
    return layout;
}

}  // namespace vkmesh::datasets
