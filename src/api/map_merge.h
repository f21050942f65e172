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
#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/frame_store.h"
#include "core/mesh.h"
#include "vk/context.h"

namespace vkmesh {

// A tile of the mesh (MergeOptions::tileSize): its index along x, y and z, the metres of its lower corner divided by
// the tile size.
using TileKey = std::array<int32_t, 3>;
// A tile's file name, as `vkmesh merge --tiles` and vkmesh.merge_maps(tiles=...) write them: tile_X_Y_Z.ply.
inline std::string tileFileName(const TileKey& t) {
    return "tile_" + std::to_string(t[0]) + "_" + std::to_string(t[1]) + "_" + std::to_string(t[2]) + ".ply";
}

struct MergeOptions {
    vk::ContextOptions device;
    bool keepFrames = true;        // carry the inputs' frame stores over (those saved beside them)
    FrameStoreOptions frames;      // the merged store's memory budget and spill folder
    bool returnMesh = false;       // fill MergeReport::mesh
    // Tiles (> 0): the mesh of the sum is also made tile by tile, tiles of tileSize metres holding whole blocks,
    // each tile meshed alone on the GPU with the blocks around it and handed to tileSink (tiles with no triangle
    // are not). Every triangle is in one tile; a vertex on a tile boundary is in each tile that uses it, with the
    // same bits: the tiles joined by vertex position are the mesh of the sum, with no seam and no duplicate. With
    // an empty output path only the tiles are made: the whole sum is never on the GPU.
    double tileSize = 0;
    std::function<void(const TileKey& tile, const Mesh& mesh)> tileSink;
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
    size_t tiles = 0, tileTriangles = 0;   // tiles handed to MergeOptions::tileSink, their triangles
    size_t tileBlocksMax = 0;              // the most blocks on the GPU for one tile (its blocks and those around it)
    double tilesMs = 0;
    std::vector<std::string> warnings;
    Mesh mesh;                             // MergeOptions::returnMesh
};

// Merges `inputs` (at least one) into `output` (written to output.tmp and renamed; its frame store beside it), and
// into tiles when MergeOptions::tileSize asks for them (output may then be empty: tiles only). Throws vkmesh::Error
// naming the file and the reason; nothing is written then.
MergeReport mergeMaps(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const MergeOptions& options);
// The same on the caller's device (MergeOptions::device is not used).
MergeReport mergeMaps(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                      const MergeOptions& options);

}  // namespace vkmesh
