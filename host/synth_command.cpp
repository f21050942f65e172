// `vkmesh synth OUT_DIR`: renders one of the built-in synthetic scenes along a camera path made for it into a
// TUM-layout folder with exact ground truth, colour included (synth/tum_sequence.h says what it writes).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "synth/tum_sequence.h"

namespace vkmesh::cli {

namespace {

struct SynthArgs {
    std::string out;
    std::string scene = "room";
    std::string path;  // empty: the scene's first path
    size_t frames = 60;
    int width = 640, height = 480;
    bool noise = false;
    uint32_t seed = 1;
    double colorNoise = 0;
    double exposureDrift = 0;
    double gtSpacing = 0.005;
};

// A built-in scene and the camera paths made for it (the first is the default): another path would look at
// empty space or run through objects.
struct SceneChoice {
    const char* name;
    synth::SyntheticScene (*make)();
    std::vector<synth::PathKind> paths;
};

const std::vector<SceneChoice>& sceneChoices() {
    static const std::vector<SceneChoice> choices{
        {"room", &synth::SyntheticScene::defaultRoom, {synth::PathKind::Orbit, synth::PathKind::Revisit}},
        {"gallery", &synth::SyntheticScene::gallery, {synth::PathKind::GalleryLoop}},
        {"twins", &synth::SyntheticScene::twinGroups, {synth::PathKind::TwinVisit}},
    };
    return choices;
}

std::string pathNames(const std::vector<synth::PathKind>& paths) {
    std::string names;
    for (synth::PathKind kind : paths) names += (names.empty() ? "" : ", ") + std::string(synth::pathName(kind));
    return names;
}

// The path `a.path` names for scene `choice`; throws Error listing the scene's paths when it is not one of them.
synth::PathKind chosenPath(const SceneChoice& choice, const std::string& path) {
    if (path.empty()) return choice.paths.front();
    for (synth::PathKind kind : choice.paths)
        if (synth::pathName(kind) == path) return kind;
    throw Error("synth: path '" + path + "' is not made for scene '" + choice.name + "' (its paths: " +
                pathNames(choice.paths) + ")");
}

int runSynth(const SynthArgs& a) {
    const SceneChoice* choice = nullptr;
    for (const SceneChoice& candidate : sceneChoices())
        if (a.scene == candidate.name) choice = &candidate;
    if (!choice) throw Error("synth: unknown scene '" + a.scene + "'");  // CLI11 checks it first
    synth::SequenceOptions options;
    options.frames = a.frames;
    options.width = a.width;
    options.height = a.height;
    options.intrinsics = synth::kinectIntrinsics(a.width, a.height);
    options.noise = a.noise;
    options.seed = a.seed;
    options.colorNoise = a.colorNoise;
    options.exposureDrift = a.exposureDrift;
    options.gtPointSpacing = a.gtSpacing;
    options.path = chosenPath(*choice, a.path);
    synth::writeTumSequence(a.out, choice->make(), options);
    std::cerr << "wrote " << a.frames << " frames of the synthetic " << choice->name << " ("
              << synth::pathName(options.path) << ") to " << a.out << "\n";
    return 0;
}

}  // namespace

Run addSynthCommand(CLI::App& app) {
    auto args = std::make_shared<SynthArgs>();
    auto* cmd = app.add_subcommand("synth", "render a synthetic depth sequence with ground truth (TUM layout)");
    cmd->add_option("OUT_DIR", args->out, "folder to write")->required();
    cmd->add_option("--frames", args->frames, "number of frames")->check(CLI::PositiveNumber);
    cmd->add_option("--width", args->width, "image width")->check(CLI::Range(16, 4096));
    cmd->add_option("--height", args->height, "image height")->check(CLI::Range(16, 4096));
    cmd->add_flag("--noise", args->noise, "Kinect-like noise and dropout");
    cmd->add_option("--seed", args->seed, "noise seed");
    cmd->add_option("--color-noise", args->colorNoise, "Gaussian colour noise per pixel and channel, sigma in 0-255 units")
        ->check(CLI::Range(0.0, 255.0));
    cmd->add_option("--exposure-drift", args->exposureDrift,
                    "colour gain varies as 1 + A sin(2 pi frame / frames) over the sequence (A in [0, 1))")
        ->check(CLI::Range(0.0, 0.999));
    // The large scenes' ground truth at the default spacing is hundreds of MB: tests that only track take less.
    cmd->add_option("--gt-spacing", args->gtSpacing, "metres between the ground-truth surface points of gt_points.ply")
        ->check(CLI::Range(0.001, 1.0));
    cmd->add_option("--scene", args->scene,
                    "room: the furnished room (paths orbit, revisit); gallery: a 10 m hall of distinct exhibits, "
                    "circled looking outward, where tracking drifts (path gallery-loop); twins: two identical object "
                    "groups in one room, a false loop (path twin-visit)")
        ->check(CLI::IsMember({"room", "gallery", "twins"}));
    cmd->add_option("--path", args->path, "camera path, one made for the scene (default: its first)")
        ->check(CLI::IsMember({"orbit", "revisit", "gallery-loop", "twin-visit"}));
    return [args] { return runSynth(*args); };
}

}  // namespace vkmesh::cli
