// `vkmesh merge`, the library side (docs/SCALING.md): saved maps added into one, with its mesh and its frames.
//
//   MergeReport r = mergeMaps({"a.vkmap", "b.vkmap"}, "ab.vkmap", MergeOptions{});
//
// The maps are read and added on the host (core/map_merge.h, where every refusal is: settings that differ, bounded
// maps, counts past what a corner holds), before a device is opened or anything is written. The sum is loaded
// into a GPU volume, which builds its mesh from scratch (GpuVolume::rebuildMesh: the mesh a run that fused every
// frame has, since the incremental mesh equals a fresh extraction), and saved. The frame stores saved beside the
// inputs are carried over, compressed as they are, so that the merged map can be corrected (docs/CORRECTION.md);
// the loop closer's state is not (its keyframes' poses belong to each input's run).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/frame_store.h"
#include "core/mesh.h"
#include "vk/context.h"

namespace vkmesh {

struct MergeOptions {
    vk::ContextOptions device;
    bool keepFrames = true;        // carry the inputs' frame stores over (those saved beside them)
    FrameStoreOptions frames;      // the merged store's memory budget and spill folder
    bool returnMesh = false;       // fill MergeReport::mesh
};

struct MergeInputReport {
    std::string path;
    size_t blocks = 0;
    uint32_t framesIntegrated = 0;
    bool frameStore = false;       // a frame store was beside it (and carried over: MergeOptions::keepFrames)
    size_t framesStored = 0;
};

struct MergeReport {
    std::vector<MergeInputReport> inputs;
    size_t blocks = 0, sharedBlocks = 0;   // in the result; coordinates held by more than one input
    uint64_t corners = 0;                  // observed corners in the result
    uint32_t framesIntegrated = 0;
    std::string frameStorePath;            // "" when no store was written
    size_t framesStored = 0;
    bool framesRenumbered = false;         // the inputs' frame indices overlapped: input k's were moved past input k-1's
    size_t meshVertices = 0, meshTriangles = 0;
    double readMs = 0, mergeMs = 0, rebuildMs = 0, saveMs = 0;
    std::vector<std::string> warnings;
    Mesh mesh;                             // MergeOptions::returnMesh
};

// Merges `inputs` (at least one) into `output` (written to output.tmp and renamed; its frame store beside it).
// Throws vkmesh::Error naming the file and the reason; nothing is written then.
MergeReport mergeMaps(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const MergeOptions& options);
// The same on the caller's device (MergeOptions::device is not used).
MergeReport mergeMaps(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                      const MergeOptions& options);

}  // namespace vkmesh
