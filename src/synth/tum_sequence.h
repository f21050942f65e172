// The TUM RGB-D folder writer for synthetic sequences (`vkmesh synth`). Part of the vkmesh_io library, not of
// the CPU core: it writes 16-bit PNGs (io/png.h). The scene, renderer and camera paths it uses are in
// synth/synthetic_scene.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/types.h"
#include "synth/synthetic_scene.h"

namespace vkmesh::synth {

struct SequenceOptions {
    size_t frames = 60;
    int width = 640, height = 480;
    // intrinsics.width/height must equal width/height above (writeTumSequence throws otherwise, rather than
    // guess how calibration made for one image size applies to another): use kinectIntrinsics(w, h).
    Intrinsics intrinsics = kinectIntrinsics(640, 480);
    bool noise = false;
    uint32_t seed = 1;  // frame i is rendered with a seed derived from (seed, i)
    PathKind path = PathKind::Orbit;
    // When not empty, exactly these camera-to-world poses are rendered, one frame each (frames and path are
    // ignored): a test can cut frames out of a path (a kidnapped camera) or splice paths together.
    std::vector<Pose> poses;
    float maxRange = 8;
    double gtPointSpacing = 0.005;  // metres between ground-truth surface samples in gt_points.ply
    double colorNoise = 0;     // sigma of per-pixel colour noise, 0-255 units (RenderOptions::colorNoise)
    // Exposure change over the sequence: frame i's gain is 1 + exposureDrift * sin(2 pi i / frames), so the
    // loop ends where it began; 0 = none. In [0, 1).
    double exposureDrift = 0;
};

// Writes a TUM-layout sequence of `scene` seen along cameraPath(options.frames, options.path), or from
// options.poses when given, into `dir` (created if needed). Each path is made for one scene (PathKind says
// which); another scene is seen from the same poses. Files:
//   depth/NNNNNN.png   uint16, metres x 5000 rounded, 0 = no measurement;
//   depth.txt          "timestamp depth/NNNNNN.png", timestamps 1.0, 1.033, ...;
//   rgb/NNNNNN.png     8-bit RGB on the depth grid (the same camera): the scene's textures, with the
//                      exposure drift and colour noise of the options;
//   rgb.txt            "timestamp rgb/NNNNNN.png", the depth frames' timestamps;
//   groundtruth.txt    "timestamp tx ty tz qx qy qz qw", camera-to-world, the same timestamps;
//   camera.json        {"fx","fy","cx","cy","depth_scale":5000,"width","height"};
//   gt_points.ply      binary little-endian point cloud (float x y z nx ny nz, uchar red green blue: the
//                      exact texture colour at gain 1) sampled uniformly by area on the visible-from-free-space
//                      surface of every object;
//   scene.json         the objects, their parameters and textures;  README.txt  what all this is.
// Throws Error naming the folder, file or value at fault (frames = 0 without poses, bad intrinsics, a pose
// that is not rigid, unwritable folder).
void writeTumSequence(const std::filesystem::path& dir, const SyntheticScene& scene,
                      const SequenceOptions& options = {});

}  // namespace vkmesh::synth
