// The one place where buffer layouts, binding numbers, push constants and workgroup sizes are defined.
// Included by the C++ host (namespace vkmesh::gpu, sizes static_assert-ed in src/gpu/layout.h) and by
// every compute shader (through structure/frame.glsl), so the two sides cannot drift apart.
#ifndef VKMESH_SHARED_LAYOUT_H
#define VKMESH_SHARED_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
namespace vkmesh::gpu {
using uint = uint32_t;
#define VKM_CONST inline constexpr uint32_t
#define VKM_CONST_FLOAT inline constexpr float
#define VKM_VEC4(name) alignas(16) float name[4]
#define VKM_ROWS3(name) alignas(16) float name[3][4]
#else
#define VKM_CONST const uint
#define VKM_CONST_FLOAT const float
#define VKM_VEC4(name) vec4 name
#define VKM_ROWS3(name) vec4 name[3]
#endif

// ---- geometry of the grid ----------------------------------------------------------------------
VKM_CONST BLOCK_SIDE = 8u;                 // cubes (and TSDF corners) per block edge
VKM_CONST VOXELS_PER_BLOCK = 512u;         // BLOCK_SIDE^3

// ---- block keys in the spatial hash ----------------------------------------------------------
// A block coordinate (x, y, z) is packed into 63 bits, 21 bits per axis, biased by 2^20, so a key is
// one 64-bit word that a single atomicCompSwap can claim. Bit 63 is never set in a key, so the all-ones
// words below can never collide with one.
VKM_CONST KEY_BITS = 21u;
VKM_CONST KEY_BIAS = 1048576u;             // 2^20: coordinates in [-2^20, 2^20) are representable
VKM_CONST KEY_AXIS_MASK = 2097151u;        // 2^21 - 1
// KEY_TOMBSTONE marks the slot of a removed key (block recycling): lookups probe past it, insertions do
// not reuse it (so a key's probe sequence never changes under a concurrent lookup); the table is rebuilt
// on the GPU when tombstones pile up (docs/MESH.md, "Recycling blocks").
#ifdef __cplusplus
inline constexpr uint64_t KEY_EMPTY = ~uint64_t(0);
inline constexpr uint64_t KEY_TOMBSTONE = ~uint64_t(0) - 1;
#elif !defined(VKMESH_HASH32)
const uint64_t KEY_EMPTY = ~uint64_t(0u);
const uint64_t KEY_TOMBSTONE = ~uint64_t(0u) - uint64_t(1u);
#endif
// The 32-bit hash path (devices without 64-bit atomics or integers; shaders compiled with -DVKMESH_HASH32,
// docs/HASH.md): a key is HASH32_KEY_WORDS words per slot, the biased x, y and z (21 bits each), each word
// claimed with its own 32-bit atomicCompSwap. Neither value below is a 21-bit coordinate.
VKM_CONST HASH32_KEY_WORDS = 3u;
VKM_CONST HASH32_WORD_EMPTY = 0xFFFFFFFFu;      // every word of an empty slot (also what a fill writes)
VKM_CONST HASH32_WORD_TOMBSTONE = 0xFFFFFFFEu;  // the first word of a removed key's slot

// Values stored beside each key: a block index into the pool, or NO_BLOCK while the key holds no block
// (just inserted this frame, or the pool was exhausted when it was inserted; the assign stage retries).
VKM_CONST NO_BLOCK = 0xFFFFFFFFu;
// Entries of the touched list after the assign stage: the block index, with FRESH_BLOCK set when the
// block was handed out this frame (its TSDF memory still holds a previous owner's data).
VKM_CONST FRESH_BLOCK = 0x80000000u;
VKM_CONST INDEX_MASK = 0x7FFFFFFFu;

// Longest probe sequence of an insertion or lookup. A table kept under half full needs a handful.
VKM_CONST HASH_MAX_PROBES = 64u;
// Longest block walk along one pixel's truncation band (3D DDA); a band of 2*trunc crosses a few blocks.
VKM_CONST RAY_MAX_BLOCKS = 32u;

// ---- workgroup sizes -----------------------------------------------------------------------
VKM_CONST WG_PIXELS_X = 8u;                // allocate_blocks: one invocation per column of
VKM_CONST WG_PIXELS_Y = 8u;                //   ALLOC_COLUMN sampled pixels (every allocationStride-th)
VKM_CONST ALLOC_COLUMN = 16u;
VKM_CONST ALLOC_TILE = 8u;                 // allocate_tiles: one invocation per tile of ALLOC_TILE x ALLOC_TILE
                                           //   sampled pixels, WG_PIXELS_X x WG_PIXELS_Y tiles per workgroup
// When allocate_tiles leaves a tile to the pixels' band walks (allocate_blocks): fewer valid depths than this,
VKM_CONST ALLOC_TILE_MIN_VALID = 48u;
// a depth farther from the tile's plane than this share of the truncation (on the synthetic room, noisy, 3 cm:
// 0.5 covers ~75 % of the tiles and allocates ~5 % more blocks than the walks; 1.0 covers more tiles but
// allocates ~9 % more, and fusion pays for every block; 0.25 covers ~30 %),
VKM_CONST_FLOAT ALLOC_TILE_MAX_RESIDUAL = 0.5f;
// or a slab whose bounding box holds more blocks than this.
VKM_CONST ALLOC_TILE_MAX_BLOCKS = 48u;
// Blocks: a block within this of the slab is claimed, which covers the rounding of the band walks' float arithmetic.
VKM_CONST_FLOAT ALLOC_SLAB_MARGIN = 1e-3f;
// Which tiles a plane covers (VolumeParamsGpu::allocationTiles, VolumeParams::allocationTileRules, the map's
// allocation mode): the first rules (maps written by the build of 2026-12-04 with --alloc-tiles) left planes with
// g < 0 and tiles without depth to the pixels; the current ones cover both. A map keeps the rules its frames were
// allocated with, since de-integrating a frame must claim the same blocks again.
VKM_CONST ALLOC_TILE_RULES_FIRST = 1u;
VKM_CONST ALLOC_TILE_RULES = 2u;
VKM_CONST WG_LIST = 64u;                   // one invocation per list entry (assign, collect)
// decide_mesh_signs: each invocation checks this many mask words of the dirty blocks for work, and a workgroup of
// WG_LIST / DECIDE_WORDS_PER_INVOCATION invocations decides its WG_LIST words' active ones together (collectDispatch).
VKM_CONST DECIDE_WORDS_PER_INVOCATION = 8u;
VKM_CONST WG_BLOCK = 128u;                 // fuse / mesh: one workgroup per block, 4 voxels per invocation
VKM_CONST VOXELS_PER_INVOCATION = 4u;      // VOXELS_PER_BLOCK / WG_BLOCK

// ---- descriptor bindings (set 0, shared by all compute stages) --------------------------------
VKM_CONST BINDING_PARAMS = 0u;         // uniform VolumeParamsGpu
VKM_CONST BINDING_COUNTERS = 1u;       // Counters (also the indirect-dispatch arguments)
VKM_CONST BINDING_HASH_KEYS = 2u;      // uint64 key per slot (32-bit path: HASH32_KEY_WORDS uints per slot)
VKM_CONST BINDING_HASH_VALUES = 3u;    // uint block index per slot
VKM_CONST BINDING_HASH_STAMPS = 4u;    // uint: frame number that last touched the slot
VKM_CONST BINDING_BLOCK_COORDS = 5u;   // ivec4 per block: block coordinate, w = hash slot
VKM_CONST BINDING_VOXEL_SDF = 6u;      // int per TSDF corner, block-major: the sum of its fused distances in fixed point
VKM_CONST BINDING_VOXEL_WEIGHT = 7u;   // float per TSDF corner: how many observations the sum holds (a whole number)
VKM_CONST BINDING_FREE_LIST = 8u;      // uint stack of free block indices
VKM_CONST BINDING_TOUCHED = 9u;        // uint list of the frame's blocks (hash slot, then block index)
VKM_CONST BINDING_DEPTH = 10u;         // the frame's images: depth (float metres) per pixel, then colour (RGBA8 uint) per pixel
VKM_CONST BINDING_MC_TABLES = 11u;     // uniform: marching-cubes tables as uint words (MC_TRIANGLE_WORDS_OFFSET)
VKM_CONST BINDING_BLOCK_LIST = 12u;    // uint list of all live blocks (for whole-volume passes)
VKM_CONST BINDING_MESH_VERTICES = 13u; // vec4 per vertex of the baseline mesh (3 per triangle)
// The incremental shared-vertex mesh (docs/MESH.md).
VKM_CONST BINDING_CUBE_STATE = 14u;    // uint per cube: type | INCOMPLETE | (chunk + 1) << 9
VKM_CONST BINDING_EDGE_VERTEX_X = 15u; // uint per cube: vertex on the owned +x edge, or EMPTY_SLOT
VKM_CONST BINDING_MESH_STAMPS = 16u;   // uint per block: frame number that last marked it dirty
VKM_CONST BINDING_DIRTY_LIST = 17u;    // uint list of the frame's dirty blocks
VKM_CONST BINDING_VERTICES = 18u;      // Vertex heap
VKM_CONST BINDING_VERTEX_OWNER = 19u;  // uint per vertex: global edge id (block * 512 + cube) * 3 + axis
VKM_CONST BINDING_VERTEX_FREE = 20u;   // uint stack of free vertex indices
// The frame's garbage, two uint lists in one buffer (one binding fewer for the passes that write both):
// [0, vertexCapacity) vertices that may have lost their last triangle (GC candidates; also the new vertices
// list_moved_vertices lists), [vertexCapacity, vertexCapacity + chunkCapacity) chunks released this frame.
VKM_CONST BINDING_GARBAGE = 21u;
VKM_CONST BINDING_CHUNK_TRIANGLES = 22u; // uint: 5 triangles x 3 vertex indices per chunk
VKM_CONST BINDING_CHUNK_FREE = 23u;    // uint stack of free chunk indices
VKM_CONST BINDING_VOXEL_COLOR = 24u;   // uint per TSDF corner: fused colour (VOXEL_COLOR_* encoding below)
VKM_CONST BINDING_EXPORT_VERTICES = 25u; // Vertex: the compacted mesh's vertices
VKM_CONST BINDING_EXPORT_INDICES = 26u;  // uint: the compacted mesh's triangles
VKM_CONST BINDING_VERTEX_REMAP = 27u;    // uint per vertex: its index in the compacted mesh
VKM_CONST BINDING_RETYPE_MASK = 28u;   // 16 uint per block: cubes that may change MC type (a corner flipped)
VKM_CONST BINDING_RETYPE_LIST = 29u;   // uint list of this frame's retype candidates: block * 512 + cube, then the changed ones
// Words per entry of the retype list: the cube, and room for it in the list of the cubes whose type changed, as
// the cube and the type mesh_claim classified it as (mesh_triangulate runs over that list only).
VKM_CONST RETYPE_LIST_WORDS_PER_CUBE = 3u;
VKM_CONST BINDING_EDGE_VERTEX_Y = 30u; // ... +y edge (one array per axis keeps each under 128 MiB for 65,536 blocks)
VKM_CONST BINDING_EDGE_VERTEX_Z = 31u; // ... +z edge
VKM_CONST BINDING_MOVED_VERTICES = 32u; // uint list of the edge slots whose vertices move_vertices moves this mesh pass
VKM_CONST BINDING_BLOCK_NEIGHBORS = 33u; // uint per block x 27: the blocks around it (frame_lists.glsl), valid while it is dirty
VKM_CONST NEIGHBORS_PER_BLOCK = 27u;      // offsets -1..1 per axis, index (x + 1) + 3 (y + 1) + 9 (z + 1)
VKM_CONST BINDING_MESH_SIGNS = 34u;     // MESH_SIGN_WORDS uint per block: with refinement, corner signs for meshing and TSDF masks
// Per block OWNED_SLOT_WORDS uint: bit (axis * VOXELS_PER_BLOCK + cube) set iff the cube's edge slot along that
// axis holds a vertex (claim sets it, GC clears it; cube_mesh.glsl). The vertex update visits only these bits.
VKM_CONST BINDING_OWNED_SLOTS = 35u;
VKM_CONST BINDING_FRAME_POSE = 36u;    // FramePoseGpu: the frame's camera pose as the passes read it
VKM_CONST BINDING_CORNER_FLIPS = 37u;  // MASK_WORDS uint per block: corners whose sign or observed state fusion flipped (frame_lists.glsl)
VKM_CONST BINDING_ALLOC_TILES = 38u;   // uint per allocation tile: 1 when allocate_tiles claimed its slab (frame_lists.glsl)
VKM_CONST BINDING_PAGE_RECORDS = 39u;  // uint: PAGE_RECORD_WORDS per block paged out or in (paging/paging.glsl)
VKM_CONST BINDING_COUNT = 40u;
VKM_CONST MASK_WORDS = 16u;            // VOXELS_PER_BLOCK / 32
VKM_CONST MASK_ALL_CUBES = 0xFFFFFFFFu; // a retype-mask word with each of its 32 cubes listed
// Per block, MESH_SIGN_WORDS uint at BINDING_MESH_SIGNS (with refinement; frame_lists.glsl): four masks with one bit
// per corner (bit `local % 32` of mask word `local / 32`), the meshing signs (decide_mesh_signs) and three masks of
// the TSDF that fusion and recycling keep exact (docs/REFINEMENT.md): sdf < 0; observed and |sdf| < refineEpsilon;
// observed (weight >= minMeshWeight). Grouped by mask word: the four words of mask word w are the uvec4 at uint
// block * MESH_SIGN_WORDS + MESH_SIGN_GROUP * w, so that one load reads a corner row's raw and observed bits
// (decide_mesh_signs' windows) or its meshing signs and observed bits (a cube's type). All zero for a free block
// (whose TSDF is zero).
VKM_CONST MESH_SIGN_WORDS = 64u;
VKM_CONST MESH_SIGN_GROUP = 4u;        // uint per mask word, one of each mask
VKM_CONST MESH_SIGN_MESHING = 0u;      // uint offsets within a group
VKM_CONST MESH_SIGN_RAW = 1u;
VKM_CONST MESH_SIGN_NEAR = 2u;
VKM_CONST MESH_SIGN_OBSERVED = 3u;
VKM_CONST OWNED_SLOT_WORDS = 48u;      // per block: 3 axes x MASK_WORDS, one bit per edge slot (BINDING_OWNED_SLOTS)
// Paging (docs/PAGING.md): one block as it waits on the host, every per-block array the map keeps, in uint words at
// these offsets of its record: x, y, z (block coordinate), the hash stamp, then TSDF sums, weights (float bits),
// colour (0 without colour), edge slots x, y, z, cube states, owned-slot masks, retype masks, mesh signs.
VKM_CONST PAGE_RECORD_SDF = 4u;
VKM_CONST PAGE_RECORD_WEIGHT = PAGE_RECORD_SDF + VOXELS_PER_BLOCK;
VKM_CONST PAGE_RECORD_COLOR = PAGE_RECORD_WEIGHT + VOXELS_PER_BLOCK;
VKM_CONST PAGE_RECORD_EDGES = PAGE_RECORD_COLOR + VOXELS_PER_BLOCK;       // 3 x VOXELS_PER_BLOCK, axis-major
VKM_CONST PAGE_RECORD_CUBE_STATE = PAGE_RECORD_EDGES + 3u * VOXELS_PER_BLOCK;
VKM_CONST PAGE_RECORD_OWNED = PAGE_RECORD_CUBE_STATE + VOXELS_PER_BLOCK;
VKM_CONST PAGE_RECORD_RETYPE = PAGE_RECORD_OWNED + OWNED_SLOT_WORDS;
VKM_CONST PAGE_RECORD_SIGNS = PAGE_RECORD_RETYPE + MASK_WORDS;
VKM_CONST PAGE_RECORD_WORDS = PAGE_RECORD_SIGNS + MESH_SIGN_WORDS;
VKM_CONST PAGE_RECORD_KEPT = 0xFFFFFFFFu;   // in a record's stamp word: the block has cubes waiting to be re-meshed and stays
// list_moved_vertices reads this many owned-slot words of one axis per invocation (commit_vertices sizes its
// dispatch with it): OWNED_SLOT_WORDS / OWNED_WORDS_PER_INVOCATION invocations per dirty block.
VKM_CONST OWNED_WORDS_PER_INVOCATION = 8u;

VKM_CONST EMPTY_SLOT = 0xFFFFFFFFu;    // an edge with no vertex
VKM_CONST CLAIMED_SLOT = 0xFFFFFFFEu;  // claimed, the winner is allocating (within one dispatch only)
VKM_CONST INVALID_INDEX = 0xFFFFFFFFu; // a triangle slot holding no triangle
VKM_CONST DEAD_REFCOUNT = 0xFFFFFFFFu; // the refcount of a vertex on the free stack
VKM_CONST CUBE_TYPE_MASK = 0xFFu;
VKM_CONST CUBE_INCOMPLETE = 0x100u;    // some triangle could not be built: rebuild when next dirty
VKM_CONST CUBE_CHUNK_SHIFT = 9u;       // chunk index + 1 in the remaining 23 bits (0 = no chunk)
VKM_CONST TRIANGLES_PER_CHUNK = 5u;
VKM_CONST CHUNK_WORDS = 15u;

// Marching-cubes tables as uint words: [0,256): edgeMask | triangleCount << 16;
// [256, 256 + 256*4): 16 edge ids per type, 4 bytes per word (15 used, 0xFF padded).
VKM_CONST MC_TRIANGLE_WORDS_OFFSET = 256u;
VKM_CONST MC_TABLE_WORDS = 1280u;

// ---- buffer layouts ------------------------------------------------------------------------------
// Constant for the life of a volume.
struct VolumeParamsGpu {
    float voxelSize;        // metres
    float truncation;       // metres
    float sdfStepsPerMetre; // fixed-point distances: SDF_STEPS_PER_TRUNCATION / truncation (core/tsdf_corner.h)
    float minMeshWeight;    // a cube is meshed only if all 8 corners have at least this weight
    uint hashCapacity;      // slots, a power of two
    uint blockCapacity;     // blocks in the pool
    uint touchedCapacity;   // entries of the touched list
    uint meshVertexCapacity;// vec4 entries of the baseline mesh buffer
    uint allocationStride;  // allocation walks the bands of every Nth pixel in x and y (fusion uses all)
    uint vertexCapacity;    // vertex heap (also the GC candidate list and the remap table)
    uint chunkCapacity;     // triangle chunks (also the chunk release list)
    uint exportTriangleCapacity;
    uint retypeCapacity;    // entries of the retype list (cubes retyped per pass)
    uint incrementalMesh;   // 1: fusion marks the cubes whose corners flip, for the incremental mesh
    uint refine;            // 1: Hamming-distance refinement of cube types (docs/REFINEMENT.md)
    float refineEpsilon;    // metres: only corners with |sdf| below it may be flipped by refinement
    uint vertexUpdate;      // VERTEX_UPDATE_*: no effect any more (every value lists the owned-slot masks), kept for the API and map files
    // Bounded maps (docs/MESH.md, "Recycling blocks"); both 0 = off, and then no recycling pass runs.
    float keepRadius;       // metres: blocks whose centre is farther from the camera are not allocated, and freed
    uint starveAfterFrames; // blocks not touched for this many frames lose starveWeight per frame; freed at 0
    float starveWeight;
    uint exportVertexCapacity; // Vertex entries of the export buffer (export_vertices counts what does not fit)
    // 1: a frame whose allocation overflowed a capacity (pool, hash, touched list) is deferred: nothing is
    // fused, the host grows what overflowed and runs the frame again (docs/MESH.md, "Capacities").
    uint deferOnOverflow;
    uint colorMode;         // COLOR_MODE_*: how fusion folds a pixel's colour into a corner's
    float colorRecency;     // COLOR_MODE_RECENT: the new colour's share, in (0, 1]
    float sdfMetresPerStep; // truncation / SDF_STEPS_PER_TRUNCATION (exact: a power-of-two division)
    uint allocationTiles;   // ALLOC_TILE_RULES_*: allocation claims the slab around a tile's plane where one fits
                            // (allocate_tiles), with those rules; 0: every sampled pixel walks its band
    uint pad1, pad2;
};
// A TSDF corner (docs/ARCHITECTURE.md, "Exact fusion"): the sum of its observations' truncated distances, each
// rounded to a step of truncation / SDF_STEPS_PER_TRUNCATION (an int), and their count (a float holding a
// whole number). Integer sums make fusion order-independent and exactly undoable: de-integrating a frame at
// the pose it was fused at subtracts the very steps it added. A corner's distance is sum / count steps.
// |step| <= SDF_STEPS_PER_TRUNCATION, so with at most SDF_MAX_COUNT observations the sum cannot overflow an
// int (4096 x 524,287 < 2^31); an observation past that count is not fused and is counted
// (Counters::observationsDropped), as is a de-integration that finds no observation to take out.
VKM_CONST SDF_STEPS_PER_TRUNCATION = 4096u;
VKM_CONST SDF_MAX_COUNT = 524287u;     // 2^19 - 1
// Which optional code a volume's pipelines are compiled with (specialisation constant VOLUME_FEATURES,
// constant_id 1, frame.glsl; vk::BindingTable::specialization()). A volume's colour mode and refinement are
// fixed when it is created, and llvmpipe runs both sides of a branch under a mask, so code switched off only
// by the uniform still costs its loads and arithmetic (the colour code made depth-only fusion 1.5x slower).
VKM_CONST VOLUME_FEATURE_COLOR = 1u;    // params.colorMode may be other than COLOR_MODE_OFF
VKM_CONST VOLUME_FEATURE_REFINE = 2u;   // params.refine may be 1
VKM_CONST VOLUME_FEATURES_ALL = 3u;
// Which way fuse_depth's and allocate_blocks' pipelines take every frame (their specialisation constant 0): their
// stages keep a pipeline that only integrates, and make one that only de-integrates when a frame first needs it;
// a pipeline built without the constant follows the frame's FramePoseGpu::deintegrate. For the same reason as the
// features above: compiled out, de-integration costs integration nothing (on the synthetic room at 3 cm fusion
// 4.49 -> 4.13 ms, allocation 2.64 -> 2.34).
VKM_CONST FUSE_BY_FRAME = 0u;
VKM_CONST FUSE_INTEGRATE = 1u;
VKM_CONST FUSE_DEINTEGRATE = 2u;
// A mesh (refined or not) keeps every vertex off its edge's ends (edgeCrossing in structure/cube_access.glsl;
// docs/REFINEMENT.md, "Vertices"), so that no two vertices share a position: one next to a corner that
// refinement flipped stops 1/FLIPPED_EDGE_MARGIN_INVERSE of the edge before it, any other at least
// 1/REFINED_EDGE_MARGIN_INVERSE from either end (exact in float for grid coordinates below 2^13).
VKM_CONST FLIPPED_EDGE_MARGIN_INVERSE = 8u;
VKM_CONST REFINED_EDGE_MARGIN_INVERSE = 1024u;
// Colour fusion (docs/COLOR.md). Off: no colour is fused (and the colour buffer is a placeholder).
VKM_CONST COLOR_MODE_OFF = 0u;
VKM_CONST COLOR_MODE_AVERAGE = 1u;     // running average with the TSDF's weight (the paper's and Open3D's rule)
VKM_CONST COLOR_MODE_RECENT = 2u;      // exponential: c' = c + colorRecency (new - c), recent frames dominate
// A corner's colour in one uint: red, green, blue in 10 bits each as 4 x the 8-bit value (0..1020, so a
// running average keeps two bits below the input's precision; rounded with a deterministic dither so that
// it is unbiased and does not stall once the weight is high), and bit 30 set once the corner has a colour.
VKM_CONST VOXEL_COLOR_BITS = 10u;
VKM_CONST VOXEL_COLOR_CHANNEL_MASK = 0x3FFu;
VKM_CONST VOXEL_COLOR_SCALE = 4u;      // stored value = 4 x 8-bit value
VKM_CONST VOXEL_COLOR_SET = 0x40000000u;
// FramePush::imageSize: width | height << 16, and this bit when the frame comes with a colour image (the
// RGBA8 words after the depth samples in BINDING_DEPTH).
VKM_CONST FRAME_HAS_COLOR = 0x80000000u;
VKM_CONST FRAME_HEIGHT_MASK = 0x7FFFu;
// Once the choice of how the vertices to move were listed (a heap scan or the dirty blocks' cubes); both are gone:
// list_moved_vertices visits the dirty blocks' owned-slot masks, whatever the value. Kept so that code and map
// files that name them still build and load.
VKM_CONST VERTEX_UPDATE_AUTO = 0u;
VKM_CONST VERTEX_UPDATE_HEAP = 1u;
VKM_CONST VERTEX_UPDATE_DIRTY = 2u;

// One mesh vertex, as stored in the heap and in the compacted export (stride 36: a renderer reads the
// position at offset 0, the normal at offset 16 and the colour at offset 32 as R8G8B8A8_UNORM).
struct Vertex {
    float px, py, pz;
    uint refcount;          // live triangles using it; DEAD_REFCOUNT while free
    float nx, ny, nz;
    uint createdFrame;      // frame number that created it (its age is now - createdFrame)
    uint color;             // red | green << 8 | blue << 16 | alpha << 24; alpha 255 when coloured, 0 when not
};

// Counters the GPU keeps; the host reads this struct back after every frame (it is small).
// The first three groups are indirect-dispatch arguments (x, y, z) and must stay 16-byte aligned.
struct Counters {
    uint touchedListDispatch[4]; // over the touched list, WG_LIST per group (raised as it grows): assign_blocks, mark_dirty
    uint blockDispatch[4];      // one workgroup per touched block
    uint listDispatch[4];       // over the live block list, one workgroup per block
    uint collectDispatch[4];    // over the dirty blocks' retype-mask words, WG_LIST per group (raised as they are listed)
    uint retypeDispatch[4];     // mesh_claim: over the retype list (raised by collect_retype as it lists); then
                                // mesh_triangulate: over the changed cubes (commit_vertices)
    uint vertexDispatch[4];     // move_vertices: over the moved list (raised by list_moved_vertices as it lists)
    uint ownedDispatch[4];      // list_moved_vertices (commit_vertices): over the dirty blocks' owned-slot masks
                                // (6 invocations per block) and the vertices created so far, WG_LIST per group
    uint candidateDispatch[4];  // over the GC candidates, WG_LIST per group (commit_chunks, for free_vertices)
    uint releaseDispatch[4];    // over the released chunks, WG_LIST per group
    // --- per frame: reset at the start of every frame ---
    uint validPixels;           // pixels with a depth inside [minDepth, maxDepth]
    uint blockRequests;         // blocks visited by all pixels' band walks (hash insert attempts)
    uint blocksFound;           //  ... of which the key was already in the table
    uint blocksInserted;        //  ... of which this invocation inserted the key
    uint hashFull;              //  ... of which found no slot within HASH_MAX_PROBES
    uint outOfRange;            // block coordinates beyond the key range (never inserted)
    uint rayTruncated;          // band walks cut at RAY_MAX_BLOCKS
    uint touchedCount;          // distinct blocks touched this frame (may exceed touchedCapacity)
    uint allocRequests;         // touched keys holding no block that asked the pool for one
    uint poolExhausted;         //  ... that got none (their key stays; retried when seen again)
    uint fusedBlocks;           // touched blocks that the fuse stage updated
    uint updatedVoxels;         // TSDF corners updated this frame
    uint dirtyCount;            // blocks re-meshed this frame (touched + neighbours reading them)
    uint cubesRetyped;          // cubes whose triangles were rebuilt
    uint vertexAllocRequests;   // edge slots claimed that asked the vertex heap for a vertex
    uint vertexExhausted;       //  ... that got none
    uint chunkAllocRequests;    // cubes that needed a triangle chunk
    uint chunkExhausted;        //  ... that got none
    uint candidateCount;        // GC candidates listed (may exceed vertexCapacity)
    uint releaseCount;          // chunks released
    uint vertexPushes;          // vertices freed
    uint chunkPushes;           // chunks freed
    uint trianglesCreated;
    uint trianglesReleased;
    uint trianglesInvalid;      // triangles not built because an edge had no vertex (heap exhausted)
    uint retypeCount;           // cubes listed for retyping this pass
    uint retypeDeferred;        // cubes that did not fit in the retype list (their bits stay for the next pass)
    // Recycling (docs/MESH.md, "Recycling blocks"): all 0 unless keepRadius or starveAfterFrames is set.
    uint outsideRadius;         // block visits of allocate_blocks beyond keepRadius (not allocated)
    uint blocksStarved;         // idle blocks whose weights decayed this frame
    uint blocksRetired;         // blocks beyond keepRadius whose weights were zeroed this frame
    uint blocksFreed;           // blocks returned to the pool (hash key -> tombstone)
    uint recycleDeferred;       // empty blocks not freed because they still owned mesh state (retried next frame)
    uint hashRebuilt;           // 1 when the hash table was rebuilt (tombstones dropped) at the start of the frame
    uint rehashLost;            // live blocks the rebuild could not re-insert within HASH_MAX_PROBES (must be 0)
    uint frameDeferred;         // 1 when commit_allocation found an overflowed capacity (deferOnOverflow): the frame fused nothing
    uint meshPending;           // 1 when the mesh passes left cubes for a follow-up pass (commit_free, deferOnOverflow)
    // Corner updates fusion could not apply exactly: an observation of a corner already holding SDF_MAX_COUNT,
    // or a de-integration of a corner holding none (a map that does not hold the frame). Must stay 0.
    uint observationsDropped;
    // Block visits of allocate_blocks that the same invocation had just made for a neighbouring pixel of its column
    // (no hash request): blockRequests = blocksFound + blocksInserted + hashFull + outOfRange + outsideRadius
    // + blocksShared.
    uint blocksShared;
    // Listed cubes whose MC type changed (or that were left INCOMPLETE): mesh_claim lists them with their new type,
    // and mesh_triangulate runs over them only (commit_vertices sizes its dispatch). At most retypeCount.
    uint cubesChanged;
    uint perFramePad2;
    // --- persistent across frames ---
    uint freeTop;               // blocks on the free list
    uint blocksInUse;           // blocks handed out of the pool
    uint liveBlockCount;        // entries written by collect_blocks (whole-volume passes)
    uint meshVertices;          // baseline mesh: vertices wanted (3 per triangle)
    uint meshVerticesDropped;   // ... that did not fit in the mesh buffer
    uint vertexFreeTop;         // vertex heap: free entries on the stack
    uint verticesInUse;
    uint vertexHighWater;       // most vertices in use at any time
    uint chunkFreeTop;
    uint chunksInUse;
    uint chunkHighWater;
    uint liveTriangles;
    uint exportVertices;        // compaction: vertices written
    uint exportTriangles;       //  ... triangles wanted
    uint exportUnreferenced;    //  ... allocated vertices with refcount 0 (0 unless GC fell behind)
    uint hashEntries;           // hash slots holding a key (with or without a block), tombstones excluded
    uint hashTombstones;        // hash slots of removed keys (0 again after a rebuild)
    // VkDrawIndexedIndirectCommand of the compacted mesh (finish_export): a renderer draws it with
    // vkCmdDrawIndexedIndirect straight from this buffer. indexCount = 0 when an export buffer overflowed.
    uint drawIndexed[5];
    uint exportDispatch[4];     // export_vertices: over the vertex heap up to its high water (plan_export)
    uint exportTriangleDispatch[4]; // export_triangles: over the triangle slots of the chunks up to their high water
    // The vertices listed for move_vertices this mesh pass: reset by commit_vertices, which runs before the
    // listing passes (so it needs no per-frame clear). In the former padding: map files hold this struct.
    uint movedCount;
    // With refinement, the corners whose meshing sign decide_mesh_signs decided from their 27-corner window this
    // mesh pass (near, at most 2 edge neighbours of their sign, window observed; every other corner takes its raw
    // sign from the masks alone): reset with the per-frame counters (CounterBuffer::recordClearFrame). Not reported; kept for tests and debugging. Also in the former padding; the struct stays a multiple of 16 bytes.
    uint signCornerCount;
};
VKM_CONST COUNTERS_PER_FRAME_OFFSET = 144u;  // byte offset of validPixels
VKM_CONST COUNTERS_PER_FRAME_SIZE = 160u;    // 40 per-frame uints

// ---- mesh deltas (docs/DELTAS.md) ---------------------------------------------------------------
// The delta passes have their own descriptor set: the shared one is full (lavapipe allows 32 storage
// buffers per stage). They compare the vertex heap and the triangle chunks with shadow copies of the
// last frame's, list what differs, and update the shadows of what they listed.
VKM_CONST DELTA_BINDING_COUNTERS = 0u;          // Counters (read: the heaps' high-water marks)
VKM_CONST DELTA_BINDING_VERTICES = 1u;          // the vertex heap
VKM_CONST DELTA_BINDING_PREV_VERTICES = 2u;     // its shadow: the heap as last reported
VKM_CONST DELTA_BINDING_CHUNKS = 3u;            // the triangle chunks
VKM_CONST DELTA_BINDING_PREV_CHUNKS = 4u;       // their shadow
VKM_CONST DELTA_BINDING_STATE = 5u;             // DeltaState (also indirect-dispatch arguments)
VKM_CONST DELTA_BINDING_VERTEX_RECORDS = 6u;    // DeltaVertexRecord list
VKM_CONST DELTA_BINDING_TRIANGLE_RECORDS = 7u;  // DeltaTriangleRecord list
VKM_CONST DELTA_BINDING_COUNT = 8u;

// A record's first word: the vertex or triangle id in the low 30 bits, the kind in the top 2.
// Vertex id = its heap index; triangle id = chunk * TRIANGLES_PER_CHUNK + slot. Both are stable while
// the vertex/triangle lives, and reused after it is removed: ADDED gives an id new content (a new
// vertex or triangle, possibly replacing one removed in the same frame).
VKM_CONST DELTA_ADDED = 0u;
VKM_CONST DELTA_CHANGED = 1u;                   // vertices only: position, normal or colour changed
VKM_CONST DELTA_REMOVED = 2u;
VKM_CONST DELTA_KIND_SHIFT = 30u;
VKM_CONST DELTA_ID_MASK = 0x3FFFFFFFu;

struct DeltaState {
    uint vertexDispatch[4];     // over [0, vertexScan), WG_LIST per group
    uint triangleDispatch[4];   // over [0, triangleScan)
    uint vertexScan;            // heap entries compared: the most ever used (high water survives a rebuild)
    uint triangleScan;          // triangle slots compared
    uint vertexRecords;         // records wanted this pass (may exceed the capacity: the host grows and re-runs)
    uint triangleRecords;
    uint vertexRecordCapacity;  // set by the host
    uint triangleRecordCapacity;
    uint pad0, pad1;
};

struct DeltaVertexRecord {
    uint idKind;
    float px, py, pz;
    float nx, ny, nz;
    uint createdFrame;
    uint color;                 // Vertex::color
};

struct DeltaTriangleRecord {
    uint idKind;
    uint v0, v1, v2;            // vertex ids (undefined for REMOVED)
};

// ---- the model in a view (docs/TRACKING.md, "Only the model in view"; shaders_comp/model_view) --------------
// Tracking draws the mesh from the vertex heap through an index list of only the triangles of the blocks that can
// be in the camera's view, so that a frame's draw costs what is in view, not the whole map. Three passes with a
// descriptor set of their own (the shared one is full): cull_view_blocks lists the live blocks in view (one
// invocation per block of the pool), list_view_chunks the triangle chunks of their cubes (one workgroup per listed
// block), emit_view_triangles the chunks' triangles (one invocation per listed chunk).
VKM_CONST VIEW_BINDING_BLOCK_COORDS = 0u;  // the block store's coordinates (BINDING_BLOCK_COORDS), w = hash slot
VKM_CONST VIEW_BINDING_HASH_VALUES = 1u;   // the hash's block per slot (BINDING_HASH_VALUES): which blocks are live
VKM_CONST VIEW_BINDING_CUBE_STATE = 2u;    // the cube states (BINDING_CUBE_STATE): each cube's chunk
VKM_CONST VIEW_BINDING_CHUNKS = 3u;        // the triangle chunks (BINDING_CHUNK_TRIANGLES)
VKM_CONST VIEW_BINDING_BLOCK_LIST = 4u;    // uint: the blocks in view (at most the pool's capacity)
VKM_CONST VIEW_BINDING_CHUNK_LIST = 5u;    // uint: their cubes' chunks (at most the chunk heap's capacity)
VKM_CONST VIEW_BINDING_INDICES = 6u;       // uint: the chunks' triangles as vertex indices, 3 per triangle (an index buffer)
VKM_CONST VIEW_BINDING_STATE = 7u;         // ModelViewState
VKM_CONST VIEW_BINDING_VERTICES = 8u;      // the vertex heap (BINDING_VERTICES): the vertices' ages, for the older map only
VKM_CONST VIEW_CUBES_PER_INVOCATION = 8u;  // list_view_chunks: two uvec4 loads of cube states per invocation
VKM_CONST WG_VIEW_BLOCK = 64u;             // list_view_chunks: VOXELS_PER_BLOCK / VIEW_CUBES_PER_INVOCATION

struct ModelViewState {
    uint draw[5];               // VkDrawIndexedIndirectCommand: indexCount = 3 x the triangles listed
    uint chunkCount;            // chunks listed
    uint pad0, pad1;
    uint blockDispatch[4];      // list_view_chunks: x = the blocks listed (one workgroup each)
    uint chunkDispatch[4];      // emit_view_triangles: over the listed chunks, WG_LIST per group
};

// The view, as the model maps' draw sees it (shaders_render/track_model.vert): a pixel u = fx x / z + cx lands in
// the framebuffer when -0.5 <= u <= width - 0.5; depth within [near, far].
struct ModelViewPush {
    VKM_ROWS3(worldToCamera);
    VKM_VEC4(intrinsics);       // fx, fy, cx, cy
    VKM_VEC4(viewport);         // width, height, near, far (metres)
    float blockSide;            // metres: BLOCK_SIDE voxels
    // A block's cubes, and so its triangles, lie within the sphere of this radius around the block's centre (half
    // its diagonal, and a margin for rounding).
    float blockRadius;
    uint blockCapacity;         // blocks in the pool
    uint hashCapacity;          // slots of the hash
    // Only triangles whose three vertices were created before this frame number are listed: the surface made before
    // the recent frames, which a loop is measured against (docs/LOOP_CLOSURE.md, "Loops against the older map").
    // 0xFFFFFFFF: every triangle (the vertices are not read).
    uint createdBefore;
    uint pad0, pad1, pad2;
};

// Push constants of every compute stage: the current frame's camera. Rigid transforms are stored as
// the 3 rows of [R | t] (x' = row.x*x + row.y*y + row.z*z + row.w), the order the CPU reference uses too.
// 128 bytes: the most lavapipe (and the Vulkan minimum) guarantees. The passes read the pose from
// FramePoseGpu, not from here: the host copies these rows there, unless camera tracking computes the pose in
// the frame's own submission.
struct FramePush {
    VKM_ROWS3(worldToCamera);
    VKM_ROWS3(cameraToWorld);
    VKM_VEC4(intrinsics);       // fx, fy, cx, cy
    uint imageSize;             // width | height << 16, | FRAME_HAS_COLOR when the frame has colour
    uint frameNumber;           // starts at 1; hash stamps start at 0
    float minDepth;             // depth samples outside [minDepth, maxDepth] are ignored
    float maxDepth;
};

// The frame's camera pose where the volume's passes read it (BINDING_FRAME_POSE; structure/frame.glsl). Written
// at the start of every frame's submission: by the host (vkCmdUpdateBuffer, the FramePush rows), or, when a
// tracked frame is fused in the submission that tracks it (docs/TRACKING.md, "One submission"), by the
// tracker's last pass (track_decide), which also decides whether the frame is fused at all.
struct FramePoseGpu {
    VKM_ROWS3(worldToCamera);
    VKM_ROWS3(cameraToWorld);
    uint skip;                  // 1: the frame is not fused (tracking lost it): no pass changes the map
    // 1: the frame is taken out of the map (de-integrated at this pose): allocation only finds blocks, fusion
    // subtracts what fusing it added (Reconstructor::correct; docs/CORRECTION.md).
    uint deintegrate;
    uint pad1, pad2;
};

// ---- camera tracking (docs/TRACKING.md; src/gpu/tracking, shaders_comp/track) ---------------------------
// The tracker's passes have a descriptor set and numbering of their own. Every per-pixel map is a pyramid
// of TRACK_LEVELS levels in one buffer: level l (width >> l by height >> l) starts at pixel
// TrackPush::offset; level 0 is the depth image's grid.
VKM_CONST TRACK_LEVELS = 3u;
VKM_CONST TRACK_BINDING_PARAMS = 0u;          // uniform TrackParamsGpu
VKM_CONST TRACK_BINDING_RAW_DEPTH = 1u;       // float per pixel: the frame's depth in metres as given (0 = none)
VKM_CONST TRACK_BINDING_DEPTH = 2u;           // float per pyramid pixel: filtered, downsampled depth (0 = none)
VKM_CONST TRACK_BINDING_VERTICES = 3u;        // vec4 per pyramid pixel: camera-space point, w = 1 (0 = none)
VKM_CONST TRACK_BINDING_NORMALS = 4u;         // vec4 per pyramid pixel: camera-space unit normal facing the
                                              // camera, w = 1 (0 = none: a missing neighbour or a depth edge)
VKM_CONST TRACK_BINDING_MODEL_POSITIONS = 5u; // vec4 per pyramid pixel: world-space point of the mesh drawn at
                                              // the model pose, w = 1 (0 = no model there)
VKM_CONST TRACK_BINDING_MODEL_NORMALS = 6u;   // vec4 per pyramid pixel: its world-space unit normal
VKM_CONST TRACK_BINDING_PARTIALS = 7u;        // float: TRACK_SUM_COUNT per workgroup of track_icp_reduce
VKM_CONST TRACK_BINDING_SUMS = 8u;            // float: TRACK_SUM_COUNT, the partials summed in a fixed order
VKM_CONST TRACK_BINDING_INTENSITY = 9u;       // float per pyramid pixel: the frame's intensity in [0, 1] (< 0: none)
VKM_CONST TRACK_BINDING_MODEL_INTENSITY = 10u;// float per pyramid pixel: the mesh's vertex colour as intensity (< 0: none)
VKM_CONST TRACK_BINDING_STATE = 11u;          // TrackStateGpu: the estimate the GPU-solved mode refines in place
VKM_CONST TRACK_BINDING_FRAME_POSE = 12u;     // the volume's FramePoseGpu (BINDING_FRAME_POSE), written by track_decide
// The ICP's reads of the per-pixel maps above, as texel buffers (samplerBuffer views of the same buffers; on
// lavapipe texelFetch is a vector gather where an SSBO load at per-lane addresses is a loop over the lanes).
VKM_CONST TRACK_BINDING_VERTEX_TEXELS = 13u;          // TRACK_BINDING_VERTICES as RGBA32F
VKM_CONST TRACK_BINDING_NORMAL_TEXELS = 14u;          // TRACK_BINDING_NORMALS as RGBA32F
VKM_CONST TRACK_BINDING_MODEL_POSITION_TEXELS = 15u;  // TRACK_BINDING_MODEL_POSITIONS as RGBA32F
VKM_CONST TRACK_BINDING_MODEL_NORMAL_TEXELS = 16u;    // TRACK_BINDING_MODEL_NORMALS as RGBA32F
VKM_CONST TRACK_BINDING_INTENSITY_TEXELS = 17u;       // TRACK_BINDING_INTENSITY as R32F
VKM_CONST TRACK_BINDING_MODEL_INTENSITY_TEXELS = 18u; // TRACK_BINDING_MODEL_INTENSITY as R32F
VKM_CONST TRACK_BINDING_COUNT = 19u;
// What one ICP iteration sums over the pixels (one float each). J = [(p - c) x n, n] (6) is the residual
// r = n . (p - q)'s derivative with respect to a step of the camera pose: a rotation about the camera's
// centre c and a translation, both in world axes (core/icp_solve.h, applyTwist); w the robust weight. The 6x6 system is symmetric: its upper triangle, row by row.
VKM_CONST TRACK_SUM_JTJ = 0u;                 // 21 values: sum w J_i J_j for i <= j
VKM_CONST TRACK_SUM_JTR = 21u;                // 6 values: sum w J_i r
VKM_CONST TRACK_SUM_WEIGHTED_ERROR = 27u;     // sum w r^2
VKM_CONST TRACK_SUM_INLIERS = 28u;            // pixels that passed the gates
VKM_CONST TRACK_SUM_SQUARED_ERROR = 29u;      // sum r^2 over the inliers (unweighted)
VKM_CONST TRACK_SUM_VALID = 30u;              // pixels with a point and a normal of the frame
VKM_CONST TRACK_SUM_MODEL_HITS = 31u;         //  ... that project onto the model (before the gates)
VKM_CONST TRACK_SUM_COUNT = 32u;
VKM_CONST WG_TRACK_PIXELS_X = 16u;            // the per-pixel passes: 16 x 16 pixels per workgroup
VKM_CONST WG_TRACK_PIXELS_Y = 16u;
VKM_CONST WG_TRACK_REDUCE = 64u;              // track_icp_reduce: invocations per workgroup, and
VKM_CONST TRACK_MAX_PIXELS_PER_INVOCATION = 64u;  //  ... at most this many pixels each one sums before the
                                              //  workgroup's tree (TrackParamsGpu::pixelsPerInvocation)
VKM_CONST TRACK_MAX_PARTIALS = 16384u;        // workgroups track_icp_sum adds up (16 Mpx per level; below lavapipe's loop cut)

// Settings of the tracker's passes (TrackerOptions), and the pose the model maps were drawn at (per frame).
struct TrackParamsGpu {
    float filterSpatialSigma;   // bilateral filter: pixels
    float filterDepthSigma;     //  ... metres
    uint filterRadius;          //  ... window half-size, pixels
    float minDepth;             // samples outside [minDepth, maxDepth] are no measurement
    float maxDepth;             // metres (0: no limit)
    float edgeJumpFraction;     // neighbours further apart than this fraction of the depth: an edge, no normal
    float modelMergeDistance;   // model maps' downsampling: fine pixels further than this from the first are not averaged
    // The photometric term (TrackerOptions::colorWeight): the frame's intensity against the mesh's vertex colours
    // drawn at the model pose, added to the geometric system with this weight per pixel (0: off).
    float colorWeight;
    float colorHuber;           // Huber delta of the intensity residual (intensities in [0, 1])
    uint frameHasColor;         // 1 when this frame's intensity pyramid holds an image
    // The GPU-solved mode (track_icp_solve): a level stops once a step rotates less than stopRotation radians
    // and moves less than stopTranslation metres (TrackerOptions).
    float stopRotation;
    float stopTranslation;
    VKM_ROWS3(modelWorldToCamera); // the inverse of the pose the model maps were drawn at
    // Pixels each invocation of track_icp_reduce sums in order (at most TRACK_MAX_PIXELS_PER_INVOCATION): few
    // on a GPU, which wants many workgroups; many on a CPU device, where each workgroup costs (lavapipe:
    // 64 instead of 16 is 0.65x the ICP time at 640 x 480, docs/RESULTS.md).
    uint pixelsPerInvocation;
    uint pad0, pad1, pad2;
    // The loss policy (TrackerOptions; PoseTracker), for track_decide: the last tracked pose, the recent
    // frames' mean inlier RMSE and share (0: none yet) and the bounds.
    VKM_ROWS3(lastTrackedCameraToWorld);
    float minInliers;
    float minInlierFraction;
    float minConditioning;
    float maxJumpMetres;
    float maxJumpDegrees;
    float maxErrorRise;
    float minErrorForRise;
    float recentRmse;
    float recentInlierShare;    // the recent tracked frames' mean inlier share (0: none yet)
    float minShareOfRecent;
    float pad3, pad4;
};

// Push constants of the tracker's compute passes.
struct TrackPush {
    VKM_ROWS3(cameraToWorld);     // the frame's pose as estimated so far
    VKM_VEC4(intrinsics);         // fx, fy, cx, cy of this level
    uint size;                    // width | height << 16 of this level (track_icp_sum: the number of partials)
    uint offset;                  // this level's first pixel in the pyramid buffers
    uint finerOffset;             // downsampling: the finer level's first pixel
    uint finerWidth;              //  ... and its width
    // Association at this level: the model point within distanceGate metres, the normals within the angle
    // whose cosine is normalGateCos; Huber weight 1 below huberDelta metres, huberDelta / |r| above.
    float distanceGate;
    float normalGateCos;
    float huberDelta;
    uint flags;                   // TRACK_FLAG_*, and the level in bits TRACK_FLAG_LEVEL_SHIFT..
};
// TrackPush::flags. With TRACK_FLAG_STATE the ICP passes read the estimate from TrackStateGpu (which
// track_icp_solve updates) instead of cameraToWorld, and do nothing once their level has stopped.
VKM_CONST TRACK_FLAG_STATE = 1u;
// With TRACK_FLAG_CHECKERBOARD track_icp_reduce visits only the level's pixels with x + y even (half of them, every
// row; the level's width is even): TrackerOptions::checkerboard at the finest level.
VKM_CONST TRACK_FLAG_CHECKERBOARD = 2u;
VKM_CONST TRACK_FLAG_LEVEL_SHIFT = 8u;

// The GPU-solved mode's state (docs/TRACKING.md, "One submission"): every ICP iteration's solve pass reads the
// sums, solves the 6x6 system in float and moves the estimate, so the host waits once per frame instead of
// once per iteration. The host writes the initial estimate and reads the rest back.
struct TrackStateGpu {
    VKM_ROWS3(cameraToWorld);     // the estimate so far
    uint stoppedLevel;            // level + 1 of the level whose last step was tiny (its remaining iterations
                                  // do nothing); 0: none
    uint unsolvedLevels;          // bit l: a system of level l could not be solved (the level stopped there)
    uint iterations;              // iterations solved (all levels)
    uint pad;
    float finalSums[TRACK_SUM_COUNT];   // the sums of level 0's last iteration (before its step)
    uint lostReason;              // track_decide: TRACK_LOST_* (TRACK_TRACKED: the frame is fused)
    float conditioning;           // track_decide: smallest / largest eigenvalue of level 0's last system
    uint pad1, pad2;
};
// Why a frame is lost (PoseTracker's checks, in the order it makes them; track_decide, trackingLoss()).
VKM_CONST TRACK_TRACKED = 0u;
VKM_CONST TRACK_LOST_NO_DEPTH = 1u;
VKM_CONST TRACK_LOST_NO_MODEL = 2u;
VKM_CONST TRACK_LOST_FEW_INLIERS = 3u;
VKM_CONST TRACK_LOST_ILL_CONDITIONED = 4u;
VKM_CONST TRACK_LOST_JUMP = 5u;
VKM_CONST TRACK_LOST_TURN = 6u;
VKM_CONST TRACK_LOST_ERROR_ROSE = 7u;
VKM_CONST TRACK_LOST_SHARE_FELL = 8u;
#ifdef __cplusplus
}  // namespace vkmesh::gpu
#endif
#endif
