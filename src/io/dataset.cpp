// Dataset: detects a folder's layout, calls that layout's reader (src/io/datasets/*_reader.cpp) and applies
// what is common to every layout: calibration precedence, maxFrames, frame 0's image size, colour
// registration; then loads frames.
#include "io/dataset.h"
#include "io/color_registration.h"
#include "io/datasets/layout_reader.h"
#include "io/datasets/recording_source.h"
#include "io/parsers.h"
#include "io/recordings/container.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace vkmesh {

namespace fs = std::filesystem;
using namespace io::text;
using namespace datasets;

namespace {

// Which layout's files a folder holds; picks the reader, and finds datasets in subfolders for the
// error message when the user passes a parent folder.
struct LayoutFiles {
    bool tumList = false;              // depth.txt or associations.txt
    std::vector<fs::path> logs;        // *.log trajectories
    bool depthDir = false;             // depth/ (Redwood)
    bool depthDirHasPngs = false;      // depth/*.png
    std::vector<SevenScenesFrame> seven;
    bool cameraJson = false;
    bool folderDepthPngs = false;      // *.png in the folder layout's depth folder (depth/ or the folder itself)
    bool redwood() const { return !logs.empty() && depthDir; }
    // Only a depth/ folder of PNGs: Redwood without its trajectory, unless a camera.json says it is a
    // calibrated plain folder (which has no default calibration to guess from).
    bool redwoodWithoutLog() const { return logs.empty() && depthDirHasPngs && !cameraJson; }
    bool folder() const { return cameraJson && folderDepthPngs; }
    bool any() const { return tumList || redwood() || !seven.empty() || redwoodWithoutLog() || folder(); }
};

LayoutFiles scanLayout(const fs::path& dir) {
    LayoutFiles f;
    std::error_code ec;
    f.tumList = fs::is_regular_file(dir / "depth.txt", ec) || fs::is_regular_file(dir / "associations.txt", ec);
    f.logs = filesWithExtension(dir, ".log");
    f.depthDir = fs::is_directory(dir / "depth", ec);
    f.depthDirHasPngs = f.depthDir && !filesWithExtension(dir / "depth", ".png").empty();
    f.seven = listSevenScenesFrames(dir);
    f.cameraJson = fs::is_regular_file(dir / "camera.json", ec);
    f.folderDepthPngs = !filesWithExtension(folderLayoutDepthDir(dir), ".png").empty();
    return f;
}

// A colour image file, decoded (JPEG or PNG, 8-bit). Throws Error naming the file.
ColorImage readColorFile(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error("cannot open colour image " + file.string());
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error("error while reading colour image " + file.string());
    return io::decodeColorImage(bytes, file.string());
}

}  // namespace

std::string toString(DatasetKind kind) {
    switch (kind) {
        case DatasetKind::TUM: return "TUM RGB-D";
        case DatasetKind::ICLNUIM: return "ICL-NUIM";
        case DatasetKind::Redwood: return "Redwood";
        case DatasetKind::SevenScenes: return "7-Scenes";
        case DatasetKind::Folder: return "folder";
        case DatasetKind::RosBag: return "ROS 1 bag";
        case DatasetKind::RealSenseBag: return "RealSense bag";
        case DatasetKind::Mcap: return "MCAP";
        case DatasetKind::Rosbag2: return "rosbag2";
    }
    return "unknown";
}

std::unique_ptr<Dataset> Dataset::open(const fs::path& folderIn, const DatasetOptions& options) {
    // Options first: a bad command-line value is reported before any file is touched.
    if (options.depthScale && !(std::isfinite(*options.depthScale) && *options.depthScale > 0))
        throw Error("depth scale " + fmt(*options.depthScale) + " must be a positive finite number");
    if (!(std::isfinite(options.maxDepth) && options.maxDepth >= 0))
        throw Error("max depth " + fmt(options.maxDepth) + " must be a finite number >= 0 (0 = no limit)");
    if (options.intrinsics) checkIntrinsics(*options.intrinsics, "--intrinsics");

    std::error_code ec;
    if (!fs::exists(folderIn, ec)) throw Error("dataset folder " + folderIn.string() + " does not exist");
    // A recording is a file (or a rosbag2 folder), recognised by its content rather than its name.
    const bool isRecording = io::recording::detectContainer(folderIn) != io::recording::ContainerKind::None;
    if (!isRecording && !fs::is_directory(folderIn, ec))
        throw Error("dataset path " + folderIn.string() +
                    " is neither a folder nor a recording (a ROS 1 bag, an MCAP file, a rosbag2 .db3 or folder)");
    // Canonical so that "seq/", "." or a symlink still give the real folder name, which carries the
    // sequence name that selects TUM/ICL intrinsics.
    fs::path folder = fs::weakly_canonical(fs::absolute(folderIn), ec);
    if (ec) folder = fs::absolute(folderIn).lexically_normal();
    std::string folderName = lower(folder.filename().string());

    // --- detect the layout ---
    Layout layout;
    LayoutFiles files = isRecording ? LayoutFiles{} : scanLayout(folder);
    if (isRecording) {
        layout = readRecording(folder, options);
    } else if (files.tumList) {
        layout = readTum(folder, folderName, options.requirePoses);
    } else if (files.redwood()) {
        if (files.logs.size() > 1) {
            std::string names;
            for (const auto& l : files.logs) names.append(names.empty() ? "" : " ").append(l.filename().string());
            throw Error("Redwood layout in " + folder.string() + ": several .log trajectories (" + names +
                        "); keep one");
        }
        layout = readRedwood(folder, files.logs.front(), options.requirePoses);
    } else if (!files.seven.empty()) {
        layout = readSevenScenes(folder, files.seven, options.requirePoses);
    } else if (files.redwoodWithoutLog()) {
        layout = readRedwood(folder, std::nullopt, options.requirePoses);
    } else if (files.folder()) {
        layout = readFolder(folder, options.requirePoses);
    } else {
        const std::string lookedFor =
            "looked for: depth.txt or associations.txt with groundtruth.txt (TUM RGB-D, ICL-NUIM), "
            "a *.log trajectory with a depth/ folder of PNGs (Redwood), "
            "frame-NNNNNN.depth.png with frame-NNNNNN.pose.txt (7-Scenes), "
            "16-bit depth PNGs in depth/ or the folder itself with a camera.json (no poses; " + kTrackingHint + ")";
        // A parent folder (a 7-Scenes scene with seq-XX folders, a folder of sequences) is a common
        // mistake; which sequence to fuse is the user's choice, so name the candidates instead of guessing.
        std::vector<std::string> subs;
        for (const auto& e : fs::directory_iterator(folder, ec))
            if (e.is_directory(ec) && scanLayout(e.path()).any()) subs.push_back(e.path().filename().string());
        std::sort(subs.begin(), subs.end(), naturalLess);
        if (!subs.empty()) {
            std::string list;
            for (const auto& n : subs) list.append(list.empty() ? "" : ", ").append(n);
            throw Error("no dataset directly in " + folder.string() + ", but its subfolders " + list +
                        " hold one each; pass one of them, e.g. " + (folder / subs.front()).string() + " (" +
                        lookedFor + ")");
        }
        if (files.folderDepthPngs)
            throw Error(folder.string() + " holds .png images but no camera.json: a plain folder of depth images needs "
                        "one with fx, fy, cx, cy and depth_scale; " + lookedFor);
        throw Error("no recognised dataset layout in " + folder.string() + "; " + lookedFor);
    }

    std::unique_ptr<Dataset> ds(new Dataset());
    ds->kind_ = layout.kind;
    ds->folder_ = folder;
    ds->invalidRaw_ = layout.invalidRaw;
    ds->maxDepth_ = options.maxDepth;
    ds->warnings_ = std::move(layout.warnings);
    ds->skippedFrames_ = layout.skipped;
    ds->recording_ = layout.recording;
    ds->description_ = layout.description;

    // --- calibration: DatasetOptions > camera.json > the sequence's own file (7-Scenes) > the layout's preset ---
    fs::path cameraJson = folder / "camera.json";
    std::optional<io::CameraJson> camera;
    if (!isRecording && fs::is_regular_file(cameraJson, ec)) {
        camera = readCameraJson(cameraJson);
        if (!camera->ignoredKeys.empty()) {
            std::string keys;
            for (const auto& key : camera->ignoredKeys) keys += (keys.empty() ? "" : ", ") + key;
            ds->warnings_.push_back(cameraJson.string() + ": ignored unknown keys " + keys +
                                    " (known: fx, fy, cx, cy, depth_scale, width, height, color_fx, color_fy, color_cx, color_cy, "
                                    "color_width, color_height, depth_to_color)");
        }
    }
    // The preset is read only when something is left to it, so that a fully calibrated folder needs no data files.
    const bool intrinsicsGiven = options.intrinsics || (camera && camera->hasAllIntrinsics()) || layout.folderIntrinsics;
    const bool scaleGiven = options.depthScale || (camera && camera->depthScale) || layout.ownDepthScale;
    Intrinsics k;
    double scale = 0;
    if ((!intrinsicsGiven || !scaleGiven) && layout.preset.empty()) {
        std::string missing;
        auto need = [&](const char* key, bool given) {
            if (!given) missing += (missing.empty() ? "" : ", ") + std::string(key);
        };
        const bool allFromOptions = bool(options.intrinsics);
        need("fx", allFromOptions || (camera && camera->fx));
        need("fy", allFromOptions || (camera && camera->fy));
        need("cx", allFromOptions || (camera && camera->cx));
        need("cy", allFromOptions || (camera && camera->cy));
        need("depth_scale", scaleGiven);
        throw Error(cameraJson.string() + ": a " + toString(layout.kind) +
                    " dataset has no default calibration, so camera.json must give fx, fy, cx, cy and depth_scale "
                    "(or --intrinsics, --depth-scale); missing " + missing);
    }
    if (!intrinsicsGiven || !scaleGiven) {
        const CameraPreset preset = loadCameraPreset(layout.preset);
        k = preset.intrinsics;
        scale = preset.depthScale;
        if (!intrinsicsGiven && !layout.intrinsicsWarning.empty())
            ds->warnings_.push_back(layout.intrinsicsWarning + " " + fmt(k.fx) + " " + fmt(k.fy) + " " + fmt(k.cx) + " " +
                                    fmt(k.cy) + " (give --intrinsics or a camera.json)");
    }
    if (layout.folderIntrinsics) k = *layout.folderIntrinsics;
    if (layout.ownDepthScale) scale = *layout.ownDepthScale;
    if (camera) {
        const io::CameraJson& c = *camera;
        if (c.fx) k.fx = float(*c.fx);
        if (c.fy) k.fy = float(*c.fy);
        if (c.cx) k.cx = float(*c.cx);
        if (c.cy) k.cy = float(*c.cy);
        if (c.depthScale) scale = *c.depthScale;
    }
    if (options.intrinsics) {
        k.fx = options.intrinsics->fx;
        k.fy = options.intrinsics->fy;
        k.cx = options.intrinsics->cx;
        k.cy = options.intrinsics->cy;
    }
    if (options.depthScale) scale = *options.depthScale;
    // A negative fy flips the image vertically: right for ICL-NUIM's poses (its default has one), a mirrored
    // reconstruction anywhere else.
    if (k.fy < 0 && layout.kind != DatasetKind::ICLNUIM)
        throw Error(std::string(options.intrinsics ? "--intrinsics" : cameraJson.string()) + ": fy = " + fmt(k.fy) +
                    " is negative, which mirrors the " + toString(layout.kind) +
                    " reconstruction upside down (only ICL-NUIM's poses use a negative fy); give a positive fy");
    ds->depthScale_ = scale;

    // --- frames ---
    if (options.maxFrames > 0 && layout.frames.size() > options.maxFrames) layout.frames.resize(options.maxFrames);
    ds->hasPoses_ = std::any_of(layout.frames.begin(), layout.frames.end(), [](const FrameInfo& f) { return f.hasPose; });
    for (size_t i = 0; i < layout.frames.size(); ++i) {
        layout.frames[i].index = i;
        // A listed file that is missing fails now rather than minutes into a reconstruction.
        if (!isRecording && !fs::is_regular_file(layout.frames[i].depthPath, ec))
            throw Error("depth image " + layout.frames[i].depthPath.string() + " (frame " + std::to_string(i) +
                        ") does not exist");
    }
    // Colour files that are listed but missing are found now, like depth, but cost only that frame's colour.
    size_t withColor = 0, missingColor = 0;
    for (FrameInfo& f : layout.frames) {
        if (f.colorPath.empty()) continue;
        if (isRecording || fs::is_regular_file(f.colorPath, ec)) {
            ++withColor;
            continue;
        }
        if (missingColor++ < kMaxFrameWarnings)
            ds->warnings_.push_back("colour image " + f.colorPath.string() + " (frame " + std::to_string(f.index) +
                                    ") does not exist; that frame has no colour");
        f.colorPath.clear();
    }
    if (missingColor > kMaxFrameWarnings)
        ds->warnings_.push_back("... and " + std::to_string(missingColor - kMaxFrameWarnings) + " more missing colour images");
    if (layout.framesWithoutColor > kMaxFrameWarnings)
        ds->warnings_.push_back("... and " + std::to_string(layout.framesWithoutColor - kMaxFrameWarnings) +
                                " more depth frames without a colour image");
    ds->hasColor_ = withColor > 0;
    if (!ds->hasColor_) ds->warnings_.push_back("no colour images: depth only");
    ds->frames_ = std::move(layout.frames);

    // The image size comes from frame 0; loadDepth holds every other frame to it.
    if (isRecording) {
        const DepthImage first = ds->recording_->loadDepth(0, scale, 0);
        k.width = first.width;
        k.height = first.height;
    } else {
        cv::Mat first = readRawDepth(ds->frames_.front().depthPath);
        k.width = first.cols;
        k.height = first.rows;
    }
    const std::string firstName = isRecording ? ds->frames_.front().depthRecord : ds->frames_.front().depthPath.string();
    // A calibration that states its image size must match the images: fusing 320x240 images with 640x480
    // intrinsics gives a plausible-looking but wrong mesh.
    if (camera && ((camera->width && *camera->width != k.width) || (camera->height && *camera->height != k.height)))
        throw Error(cameraJson.string() + ": calibration for " +
                    (camera->width ? std::to_string(*camera->width) : std::string("?")) + "x" +
                    (camera->height ? std::to_string(*camera->height) : std::string("?")) + " images, but depth image " +
                    firstName + " (frame 0) is " + std::to_string(k.width) + "x" + std::to_string(k.height));
    // Without a stated size, a principal point outside the image is the sign of the same mistake; only a
    // warning, since nothing says which of the two is wrong (and tiny test images use default intrinsics).
    if (k.cx < 0 || k.cx > k.width || k.cy < 0 || k.cy > k.height)
        ds->warnings_.push_back("principal point cx=" + fmt(k.cx) + " cy=" + fmt(k.cy) + " lies outside the " +
                                std::to_string(k.width) + "x" + std::to_string(k.height) + " depth images (" +
                                firstName + "): are the intrinsics for another image size?");
    ds->intrinsics_ = k;

    // A recording's colour camera: its own intrinsics, and extrinsics where the recording has them.
    if (layout.colorCamera && ds->hasColor_) {
        ds->colorIntrinsics_ = layout.colorCamera->intrinsics;
        ds->depthToColor_ = layout.colorCamera->depthToColor;
    }

    // A colour camera of its own (camera.json color_*): every depth pixel's ray, projected into it, gives the
    // remap that puts colour on the depth grid. The colour images' size is the file's, or frame 0's image.
    // With depth_to_color (a baseline between the cameras) colour is registered through depth, per frame;
    // the colour camera's intrinsics are then its own (color_*) or, without them, the depth camera's.
    if (camera && (camera->colorFx || camera->depthToColor) && ds->hasColor_) {
        Intrinsics ck = camera->colorFx ? Intrinsics{float(*camera->colorFx), float(*camera->colorFy), float(*camera->colorCx),
                                                     float(*camera->colorCy), camera->colorWidth.value_or(0),
                                                     camera->colorHeight.value_or(0)}
                                        : Intrinsics{k.fx, k.fy, k.cx, k.cy, 0, 0};
        if (ck.width == 0 || ck.height == 0) {
            const auto withColor = std::find_if(ds->frames_.begin(), ds->frames_.end(),
                                                [](const FrameInfo& f) { return !f.colorPath.empty(); });
            try {
                std::ifstream in(withColor->colorPath, std::ios::binary);
                const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
                const ColorImage c = io::decodeColorImage(bytes, withColor->colorPath.string());
                if (ck.width == 0) ck.width = c.width;
                if (ck.height == 0) ck.height = c.height;
            } catch (const Error& e) {
                ds->warnings_.push_back(std::string(e.what()) + "; without color_width and color_height in " +
                                        cameraJson.string() + " the colour images' size is unknown: depth only");
                ds->hasColor_ = false;
            }
        }
        if (ds->hasColor_ && camera->depthToColor) {
            ds->colorIntrinsics_ = ck;
            ds->depthToColor_ = *camera->depthToColor;
        } else if (ds->hasColor_) {
            ds->colorIntrinsics_ = ck;
            ds->colorMapX_.resize(size_t(k.width) * k.height);
            ds->colorMapY_.resize(size_t(k.width) * k.height);
            for (int v = 0; v < k.height; ++v)
                for (int u = 0; u < k.width; ++u) {
                    const size_t i = size_t(v) * k.width + u;
                    ds->colorMapX_[i] = float(ck.fx * ((u - k.cx) / k.fx) + ck.cx);
                    ds->colorMapY_[i] = float(ck.fy * ((v - k.cy) / k.fy) + ck.cy);
                }
        }
    }
    return ds;
}

const FrameInfo& Dataset::frame(size_t i) const {
    if (i >= frames_.size())
        throw Error("frame " + std::to_string(i) + " out of range: the dataset " + folder_.string() + " has " +
                    std::to_string(frames_.size()) + " frames");
    return frames_[i];
}

DepthImage Dataset::loadDepth(size_t i) const {
    const FrameInfo& f = frame(i);
    if (recording_) {
        DepthImage d = recording_->loadDepth(i, depthScale_, maxDepth_);
        if (d.width != intrinsics_.width || d.height != intrinsics_.height)
            throw Error(f.depthRecord + ": depth image is " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                        " but frame 0's is " + std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height));
        return d;
    }
    cv::Mat raw = readRawDepth(f.depthPath);
    if (raw.cols != intrinsics_.width || raw.rows != intrinsics_.height)
        throw Error("depth image " + f.depthPath.string() + " is " + std::to_string(raw.cols) + "x" +
                    std::to_string(raw.rows) + " but frame 0 (" + frames_.front().depthPath.filename().string() +
                    ") is " + std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height));
    return io::rawDepthToMeters(raw, depthScale_, invalidRaw_, maxDepth_);
}

ColorImage Dataset::loadColor(size_t i, std::string* warning, const DepthImage* depth) const {
    const FrameInfo& f = frame(i);
    auto unusable = [&](const std::string& why) {
        if (warning) *warning = why + "; frame " + std::to_string(i) + " has no colour";
        return ColorImage{};
    };
    // A frame without an image is only worth a word when the sequence has colour elsewhere.
    if (f.colorPath.empty())
        return hasColor_ ? unusable("no colour image for depth image " + f.depthPath.filename().string()) : ColorImage{};
    const std::string name = recording_ ? f.colorRecord : f.colorPath.string();
    ColorImage image;
    try {
        image = recording_ ? recording_->loadColor(i) : readColorFile(f.colorPath);
    } catch (const Error& e) {
        return unusable(e.what());
    }
    const int w = colorIntrinsics_ ? colorIntrinsics_->width : intrinsics_.width;
    const int h = colorIntrinsics_ ? colorIntrinsics_->height : intrinsics_.height;
    const std::string expected = !colorIntrinsics_ ? "the depth images are "
                                 : recording_     ? "the colour camera info is for "
                                                  : "the colour calibration (camera.json) is for ";
    if (image.width != w || image.height != h)
        return unusable("colour image " + name + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                        " but " + expected + std::to_string(w) + "x" + std::to_string(h));
    if (!colorIntrinsics_) return image;
    if (depthToColor_) {
        // Through each pixel's depth: the colour camera sees the scene from elsewhere.
        try {
            const DepthImage loaded = depth ? DepthImage{} : loadDepth(i);
            return registerColorToDepth(image, ColorCamera{*colorIntrinsics_, *depthToColor_}, depth ? *depth : loaded,
                                        intrinsics_);
        } catch (const Error& e) {
            return unusable(name + ": " + e.what());
        }
    }

    // Bilinear resampling onto the depth grid; depth pixels outside the colour camera's view get black.
    const cv::Mat src(image.height, image.width, CV_8UC3, image.rgb.data());
    const cv::Mat mapX(intrinsics_.height, intrinsics_.width, CV_32FC1, const_cast<float*>(colorMapX_.data()));
    const cv::Mat mapY(intrinsics_.height, intrinsics_.width, CV_32FC1, const_cast<float*>(colorMapY_.data()));
    ColorImage out;
    out.width = intrinsics_.width;
    out.height = intrinsics_.height;
    out.rgb.resize(size_t(out.width) * out.height * 3);
    cv::Mat dst(out.height, out.width, CV_8UC3, out.rgb.data());  // remap writes into out.rgb directly
    try {
        cv::remap(src, dst, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
    } catch (const cv::Exception& e) {
        return unusable("cannot resample colour image " + name + ": " + e.what());
    }
    return out;
}

}  // namespace vkmesh
