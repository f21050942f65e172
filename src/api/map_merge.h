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

// ---- tiles made on their own -----------------------------------------------------------------------------------
//
// For a map one process should not hold: workers each make some tiles, reading from the inputs only the blocks those
// tiles need (map::BlockReader), never the whole map, in host memory or on the GPU.
//
//   TilePlan plan = planTiles(inputs, 2.0);                       // from the inputs' block tables only
//   mergeTiles(inputs, {plan.tiles.begin(), plan.tiles.begin() + 4}, TileOptions{{}, 2.0, sink});   // on one worker
//
// A tile made so is the tile mergeMaps(tileSize) makes from the whole sum: its blocks and one block around them, read
// from every input, added (map::merge, with all its refusals), loaded alone, meshed from scratch and cut to the tile's
// own cubes' triangles; the same triangles, vertex position and normal bits.

struct TilePlan {
    std::vector<TileKey> tiles;   // every tile holding a block of the sum, in key order
    size_t blocks = 0;            // blocks of the sum (distinct block coordinates over the inputs)
    uint32_t framesIntegrated = 0;   // the sum's (the inputs' added)
};
// Reads the inputs' headers and block tables (not their corners) and checks that they add up (settings, bounded maps,
// colour mode, sections: map::merge's refusals that need no corner). Throws vkmesh::Error naming the file.
TilePlan planTiles(const std::vector<std::filesystem::path>& inputs, double tileSize);

struct TileOptions {
    vk::ContextOptions device;
    double tileSize = 0;   // metres (> 0), as for planTiles and MergeOptions::tileSize
    // Each tile with a triangle; tiles with none are not handed over.
    std::function<void(const TileKey& tile, const Mesh& mesh)> tileSink;
};

struct TileReport {
    TileKey tile{};
    size_t blocksRead = 0;     // blocks of corners read from the inputs (the tile's and those around it, from each input holding them)
    size_t blocksMeshed = 0;   // blocks of their sum, loaded on the GPU (0: the tile holds no block of the sum)
    size_t vertices = 0, triangles = 0;   // the tile's mesh (0 triangles: not handed to the sink)
    double readMs = 0, meshMs = 0;        // reading and adding; loading, meshing and cutting
};

struct TilesReport {
    std::vector<TileReport> tiles;   // in the order asked for
    // The most blocks of corners held at once: in host memory (those read for one tile and their sum, both alive
    // while they are added) and on the GPU (the sum, one tile at a time). Besides them each input's block table is
    // kept, 16 bytes a block (tableBlocks entries).
    size_t hostBlocksMax = 0, gpuBlocksMax = 0;
    size_t tableBlocks = 0;
    double openMs = 0;               // the inputs' headers and block tables, and the device when it is opened here
};

// Makes `tiles` (keys as planTiles lists them; a tile holding no block of the sum gives nothing) of the sum of
// `inputs`, reading only their blocks, and hands each to options.tileSink. Throws vkmesh::Error naming the file and
// the reason (what map::merge refuses, checked on the corners read).
TilesReport mergeTiles(const std::vector<std::filesystem::path>& inputs, const std::vector<TileKey>& tiles, const TileOptions& options);
// The same on the caller's device (TileOptions::device is not used).
TilesReport mergeTiles(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::vector<TileKey>& tiles,
                       const TileOptions& options);

}  // namespace vkmesh
