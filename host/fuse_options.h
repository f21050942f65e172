// `vkmesh fuse`'s options: what the command line says, registered in one place (addFuseOptions), checked before any
// work (check), and turned into the Mapper's options (mapperOptions). The option names and their meaning are an
// interface (users' scripts): add, never rename.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "api/mapper.h"
#include "cli_options.h"

namespace CLI {
class App;
}

namespace vkmesh::cli {

struct FuseArgs {
    DatasetArgs data;
    VolumeOptions volume;
    DeviceArgs device;
    MeshOutputArgs output;   // -o, --simplify
    std::string statsPath;
    bool growHeaps = false;
    bool quiet = false;
    bool noStageTimes = false;
    bool passTimes = false;
    bool analyseMesh = false;   // --analyse-mesh: the baseline's vertex count, regularity and topology in --stats
    // Pictures while fusing (drawn from the GPU mesh buffers) and the mesh-delta stream.
    uint32_t renderEvery = 0;
    std::string renderDir;
    std::string renderView = "sensor";
    std::string renderColor = "auto";
    std::string deltasPath;
    // The live browser viewer (docs/VIEWER.md): port (-1: not serving), address, how long to keep serving after
    // the last frame (< 0: until Ctrl-C).
    int servePort = -1;
    std::string serveHost = "127.0.0.1";
    double serveLinger = -1;
    // Maps (docs/MAPFILE.md): continue from one, skip the frames it holds, save the state after the last frame.
    std::string loadPath;
    std::string savePath;
    size_t firstFrame = 0;
    // The frame store (docs/CORRECTION.md): kept with a saved map so that `vkmesh correct` can re-fuse frames.
    bool keepFrames = false, noKeepFrames = false;
    double framesBudgetMb = 1024;
    std::string framesSpill;
    // Camera tracking (docs/TRACKING.md): estimate every pose after the first against the mesh.
    bool track = false;
    std::string trajectoryPath;        // the pose used for every frame, TUM format
    std::string trackIterations;       // "3,4,4": ICP iterations per level, finest first (empty: by size)
    float trackColorWeight = gpu::TrackerOptions{}.colorWeight;   // the photometric term's weight (0: off)
    std::string trackSolve = "host";   // where the ICP systems are solved: host (double, a wait per iteration) or gpu
    int trackDownsample = gpu::TrackerOptions{}.downsample;   // track on frames downsampled by 1, 2 or 4 (0: by width)
    int trackModelReuse = gpu::TrackerOptions{}.modelReuseFrames;   // frames in a row that may reuse the model maps
    // Loop closure and relocalisation (docs/LOOP_CLOSURE.md): on with --track unless --no-loop-closure (or
    // --no-keep-frames, since a loop re-fuses the kept frames); --loop-closure asks for it explicitly.
    bool loopClosure = false, noLoopClosure = false;
    std::string trajectoryOnlinePath;  // the poses as they were when each frame was fused
    size_t correctionsPerFrame = 2;    // queued corrections re-fused before each frame
    int loopPlaceCandidates = kDefaultLoopPlaceCandidates;   // loop candidates by place (slam::LoopClosureOptions)
    const CLI::App* cmd = nullptr;     // which options were given (a loaded map's settings fill the others)

    bool given(const char* option) const;
    bool serving() const { return servePort >= 0; }
    // Whether the run closes loops and relocalises: asked for (--loop-closure), or by default with --track where its
    // frames (width x height; 0 x 0: not known yet) are no smaller than place recognition's image (80 x 60).
    bool closesLoops(int width = 0, int height = 0) const;
    // --track without --no-loop-closure whose frames are too small for the default (closesLoops(width, height) is false).
    bool loopClosureDroppedForSize(int width, int height) const { return closesLoops() && !closesLoops(width, height); }
    // The combinations that cannot work, before anything is opened (Error naming the options).
    void check() const;
    // The volume's settings for the dataset's images; with `map` (--load) the map's where the command line gave none.
    gpu::GpuVolumeConfig volumeConfig(const Intrinsics& intrinsics, bool datasetHasColor, const map::MapData* map) const;
    // The Mapper's options around `volume`: the tracker, the corrections' budget and the loop closer.
    MapperOptions mapperOptions(const gpu::GpuVolumeConfig& volume) const;
    FrameStoreOptions frameStoreOptions() const;
};

void addFuseOptions(CLI::App* cmd, FuseArgs& args);

}  // namespace vkmesh::cli
