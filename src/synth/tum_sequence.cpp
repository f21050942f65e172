#include "synth/tum_sequence.h"

#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "io/png.h"

namespace vkmesh::synth {

namespace {

// The sensor's raw units: 1/5000 m in a uint16 PNG (TUM RGB-D convention).
constexpr double kDepthScale = 5000.0;
constexpr double kFirstTimestamp = 1.0;
constexpr double kFramePeriod = 0.033;

std::ofstream openForWriting(const std::filesystem::path& path, std::ios::openmode mode = std::ios::out) {
    std::ofstream out(path, mode | std::ios::trunc);
    if (!out) throw Error("cannot write '" + path.string() + "'");
    return out;
}

void finishWriting(std::ofstream& out, const std::filesystem::path& path) {
    out.close();
    if (!out) throw Error("failed while writing '" + path.string() + "' (disk full?)");
}

std::string formatTimestamp(size_t frame) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", kFirstTimestamp + kFramePeriod * static_cast<double>(frame));
    return text;
}

std::string frameFileName(size_t frame, const char* folder = "depth") {
    char text[48];
    std::snprintf(text, sizeof text, "%s/%06zu.png", folder, frame);
    return text;
}

void writeDepthPng(const std::filesystem::path& path, const DepthImage& depth) {
    std::vector<uint16_t> raw(static_cast<size_t>(depth.width) * depth.height);
    for (int y = 0; y < depth.height; ++y)
        for (int x = 0; x < depth.width; ++x) {
            const double units = std::round(static_cast<double>(depth.at(x, y)) * kDepthScale);
            // Depth beyond what 16 bits hold (13.1 m) cannot be stored: it becomes "no measurement".
            raw[static_cast<size_t>(y) * depth.width + x] = units > 0 && units <= 65535.0 ? static_cast<uint16_t>(units) : 0;
        }
    io::writeDepthPng(path, depth.width, depth.height, raw);
}

void appendLittleEndianFloat(std::string& bytes, double value) {
    const uint32_t bits = std::bit_cast<uint32_t>(static_cast<float>(value));
    for (int shift = 0; shift < 32; shift += 8) bytes.push_back(static_cast<char>((bits >> shift) & 0xFF));
}

void writeGroundTruthPly(const std::filesystem::path& path, const std::vector<SurfaceSample>& samples, double spacing) {
    std::ofstream out = openForWriting(path, std::ios::out | std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\n"
        << "comment vkmesh synthetic ground truth: true surface sampled uniformly by area, spacing " << spacing
        << " m\nelement vertex " << samples.size()
        << "\nproperty float x\nproperty float y\nproperty float z\n"
           "property float nx\nproperty float ny\nproperty float nz\n"
           "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    std::string bytes;
    bytes.reserve(samples.size() * 27);
    for (const SurfaceSample& sample : samples) {
        for (int i = 0; i < 3; ++i) appendLittleEndianFloat(bytes, sample.position[i]);
        for (int i = 0; i < 3; ++i) appendLittleEndianFloat(bytes, sample.normal[i]);
        for (int i = 0; i < 3; ++i) bytes.push_back(static_cast<char>(sample.color[i]));
    }
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    finishWriting(out, path);
}

nlohmann::json vectorJson(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json sceneJson(const SyntheticScene& scene) {
    nlohmann::json objects = nlohmann::json::array();
    for (const Object& object : scene.objects()) {
        nlohmann::json entry;
        entry["name"] = object.name;
        entry["kind"] = std::string(kindName(object.kind));
        entry["center"] = vectorJson(object.center());
        nlohmann::json rotation = nlohmann::json::array();
        for (int row = 0; row < 3; ++row) rotation.push_back(vectorJson(object.objectToWorld.linear().row(row).transpose()));
        entry["rotation"] = rotation;  // object-to-world, row-major; local axes are its columns
        const Texture& t = object.texture;
        const char* pattern = t.pattern == Texture::Pattern::Stripes   ? "stripes"
                              : t.pattern == Texture::Pattern::Checker ? "checker"
                                                                       : "uniform";
        entry["texture"] = {{"pattern", pattern}, {"period", t.period}, {"axis", t.axis}, {"offset", t.offset},
                            {"a", t.a}, {"b", t.b}};  // solid texture in the local frame (synthetic_scene.h)
        switch (object.kind) {
            case ObjectKind::RoomInterior: entry["half_extents"] = vectorJson(object.halfExtents); break;
            case ObjectKind::HalfSpace:
                entry["normal"] = vectorJson(object.objectToWorld.linear().col(2));
                entry["offset"] = object.objectToWorld.linear().col(2).dot(object.center());
                break;
            case ObjectKind::Sphere: entry["radius"] = object.radius; break;
            case ObjectKind::Torus:
                entry["radius"] = object.radius;
                entry["tube_radius"] = object.tubeRadius;
                entry["axis"] = vectorJson(object.objectToWorld.linear().col(2));
                break;
            case ObjectKind::RoundedBox:
                entry["half_extents"] = vectorJson(object.halfExtents);
                entry["edge_radius"] = object.edgeRadius;
                break;
            case ObjectKind::Cylinder:
                entry["radius"] = object.radius;
                entry["half_height"] = object.halfHeight;
                entry["axis"] = vectorJson(object.objectToWorld.linear().col(2));
                break;
        }
        objects.push_back(entry);
    }
    nlohmann::json root;
    root["description"] = "vkmesh synthetic scene: the union of these primitives; metres, world z up";
    root["sdf_sign"] = "positive in free space, negative inside matter; room_interior: free space inside the box";
    root["objects"] = objects;
    return root;
}

const char* kReadmeText =
    "Synthetic depth sequence written by vkmesh (src/synth/tum_sequence.cpp).\n"
    "\n"
    "An analytic scene (see scene.json) rendered by sphere tracing its signed distance function, so the\n"
    "camera poses, the surface and its colours are known exactly. The layout is TUM RGB-D's:\n"
    "\n"
    "  depth/NNNNNN.png  16-bit depth, metres x 5000, 0 = no measurement. Camera-frame z, not ray length.\n"
    "  depth.txt         timestamp and depth file per frame (timestamps 1.0 s, then every 0.033 s).\n"
    "  rgb/NNNNNN.png    8-bit colour on the depth image's grid (same camera, same instant): the objects'\n"
    "                    solid textures (stripes, checkers), with exposure drift and noise if asked for.\n"
    "  rgb.txt           timestamp and colour file per frame (the depth timestamps).\n"
    "  groundtruth.txt   timestamp tx ty tz qx qy qz qw: camera-to-world pose (exact), one per frame.\n"
    "  camera.json       pinhole intrinsics fx fy cx cy (pixel centres at integer coordinates), depth_scale,\n"
    "                    image size. Camera looks along +z, x right, y down.\n"
    "  gt_points.ply     ground-truth surface: points sampled uniformly by area on every object's surface\n"
    "                    with outward normals, leaving out what is hidden inside or in contact with another\n"
    "                    object. Points, not a mesh; binary little-endian float x y z nx ny nz,\n"
    "                    uchar red green blue (the exact texture colour, at the exposure of frame 0).\n"
    "  scene.json        the primitives (name, kind, centre, rotation, sizes) the scene is made of.\n"
    "\n";

}  // namespace

void writeTumSequence(const std::filesystem::path& dir, const SyntheticScene& scene, const SequenceOptions& options) {
    const std::string where = "writeTumSequence('" + dir.string() + "'): ";
    if (options.frames == 0 && options.poses.empty()) throw Error(where + "frames must be at least 1, got 0");
    if (options.width <= 0 || options.height <= 0)
        throw Error(where + "image size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                    " must be positive");
    if (options.intrinsics.width != options.width || options.intrinsics.height != options.height)
        throw Error(where + "the intrinsics are for " + std::to_string(options.intrinsics.width) + "x" +
                    std::to_string(options.intrinsics.height) + " images but the sequence is " +
                    std::to_string(options.width) + "x" + std::to_string(options.height) +
                    " (kinectIntrinsics(width, height) gives matching ones)");
    try {
        validateIntrinsics(options.intrinsics);
    } catch (const Error& e) {
        throw Error(where + e.what());
    }
    if (!std::isfinite(options.gtPointSpacing) || options.gtPointSpacing <= 0)
        throw Error(where + "gtPointSpacing = " + std::to_string(options.gtPointSpacing) + " must be positive");
    if (!std::isfinite(options.colorNoise) || options.colorNoise < 0)
        throw Error(where + "colour noise " + std::to_string(options.colorNoise) + " must be >= 0");
    if (!std::isfinite(options.exposureDrift) || options.exposureDrift < 0 || options.exposureDrift >= 1)
        throw Error(where + "exposure drift " + std::to_string(options.exposureDrift) + " must be in [0, 1)");

    std::error_code error;
    for (const char* sub : {"depth", "rgb"}) {
        std::filesystem::create_directories(dir / sub, error);
        if (error || !std::filesystem::is_directory(dir / sub))
            throw Error("cannot create folder '" + (dir / sub).string() + "': " +
                        (error ? error.message() : std::string("not a directory")));
    }

    const std::vector<Pose> poses = options.poses.empty() ? cameraPath(options.frames, options.path) : options.poses;
    RenderOptions renderOptions;
    renderOptions.maxRange = options.maxRange;
    renderOptions.noise = options.noise;
    renderOptions.colorNoise = options.colorNoise;
    for (size_t frame = 0; frame < poses.size(); ++frame) {
        renderOptions.seed = frameSeed(options.seed, frame);
        renderOptions.exposure =
            1 + options.exposureDrift * std::sin(2 * 3.14159265358979323846 * double(frame) / double(poses.size()));
        ColorImage color;
        writeDepthPng(dir / frameFileName(frame), scene.renderDepth(options.intrinsics, poses[frame], renderOptions, &color));
        io::writeColorPng(dir / frameFileName(frame, "rgb"), color);
    }

    // The index files come last: a folder with a depth.txt is complete.
    writeGroundTruthPly(dir / "gt_points.ply", sampleSurface(scene, options.gtPointSpacing), options.gtPointSpacing);
    {
        const std::filesystem::path path = dir / "scene.json";
        std::ofstream out = openForWriting(path);
        out << sceneJson(scene).dump(2) << "\n";
        finishWriting(out, path);
    }
    {
        const std::filesystem::path path = dir / "camera.json";
        nlohmann::json camera;
        camera["fx"] = options.intrinsics.fx;
        camera["fy"] = options.intrinsics.fy;
        camera["cx"] = options.intrinsics.cx;
        camera["cy"] = options.intrinsics.cy;
        camera["depth_scale"] = kDepthScale;
        camera["width"] = options.width;
        camera["height"] = options.height;
        std::ofstream out = openForWriting(path);
        out << camera.dump(2) << "\n";
        finishWriting(out, path);
    }
    {
        const std::filesystem::path path = dir / "groundtruth.txt";
        std::ofstream out = openForWriting(path);
        out << "# ground truth trajectory (camera-to-world), vkmesh synthetic scene\n"
               "# timestamp tx ty tz qx qy qz qw\n";
        for (size_t frame = 0; frame < poses.size(); ++frame) {
            const Eigen::Matrix3d rotation = poses[frame].topLeftCorner<3, 3>();
            Eigen::Quaterniond q(rotation);
            q.normalize();
            if (q.w() < 0) q.coeffs() = -q.coeffs();  // one of the two equivalent signs, for tidy files
            char line[256];
            std::snprintf(line, sizeof line, "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", formatTimestamp(frame).c_str(),
                          poses[frame](0, 3), poses[frame](1, 3), poses[frame](2, 3), q.x(), q.y(), q.z(), q.w());
            out << line;
        }
        finishWriting(out, path);
    }
    {
        const std::filesystem::path path = dir / "README.txt";
        std::ofstream out = openForWriting(path);
        const std::string pathDescription =
            options.poses.empty() ? std::string(pathName(options.path)) : std::string("given poses");
        out << kReadmeText << "Frames: " << poses.size() << ", " << options.width << "x" << options.height
            << ", noise: " << (options.noise ? "Kinect-like (seed " + std::to_string(options.seed) + ")" : "none")
            << ", path: " << pathDescription
            << ", colour noise sigma: " << options.colorNoise << ", exposure drift: " << options.exposureDrift
            << ".\n";
        finishWriting(out, path);
    }
    {
        const std::filesystem::path path = dir / "rgb.txt";
        std::ofstream out = openForWriting(path);
        out << "# color images, vkmesh synthetic scene\n# timestamp filename\n";
        for (size_t frame = 0; frame < poses.size(); ++frame)
            out << formatTimestamp(frame) << " " << frameFileName(frame, "rgb") << "\n";
        finishWriting(out, path);
    }
    {
        const std::filesystem::path path = dir / "depth.txt";
        std::ofstream out = openForWriting(path);
        out << "# depth maps, vkmesh synthetic scene\n# timestamp filename\n";
        for (size_t frame = 0; frame < poses.size(); ++frame)
            out << formatTimestamp(frame) << " " << frameFileName(frame) << "\n";
        finishWriting(out, path);
    }
}

}  // namespace vkmesh::synth
