// `vkmesh synth OUT_DIR`: renders the built-in synthetic room along a camera path into a TUM-layout folder
// with exact ground truth, colour included (synth/tum_sequence.h says what it writes).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "synth/tum_sequence.h"

namespace vkmesh::cli {

namespace {

struct SynthArgs {
    std::string out;
    std::string path = "orbit";
    size_t frames = 60;
    int width = 640, height = 480;
    bool noise = false;
    uint32_t seed = 1;
    double colorNoise = 0;
    double exposureDrift = 0;
};

int runSynth(const SynthArgs& a) {
    synth::SequenceOptions options;
    options.frames = a.frames;
    options.width = a.width;
    options.height = a.height;
    options.intrinsics = synth::kinectIntrinsics(a.width, a.height);
    options.noise = a.noise;
    options.seed = a.seed;
    options.colorNoise = a.colorNoise;
    options.exposureDrift = a.exposureDrift;
    options.path = a.path == "revisit" ? synth::PathKind::Revisit : synth::PathKind::Orbit;
    synth::writeTumSequence(a.out, synth::SyntheticScene::defaultRoom(), options);
    std::cerr << "wrote " << a.frames << " frames of the synthetic room to " << a.out << "\n";
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
    cmd->add_option("--path", args->path, "camera path")->check(CLI::IsMember({"orbit", "revisit"}));
    return [args] { return runSynth(*args); };
}

}  // namespace vkmesh::cli
