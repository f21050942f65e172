// Component: the per-frame lists (src/gpu/frame_lists.h), what one pass hands the next: the blocks a frame
// touched, the live-block list of whole-volume passes, the dirty blocks (deduplicated with per-block mesh
// stamps), the retype masks and list of cubes to re-mesh, the vertices that may have lost their last
// triangle (GC candidates) and the chunks released this frame, the vertices to move this mesh pass (their edge
// slots), the dirty blocks' neighbour blocks, and with refinement each corner's sign for meshing and the masks of
// the TSDF it is decided from. Their lengths are in Counters.
#ifndef VKMESH_FRAME_LISTS_GLSL
#define VKMESH_FRAME_LISTS_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_TOUCHED) buffer Touched { uint touched[]; };
layout(std430, set = 0, binding = BINDING_BLOCK_LIST) buffer BlockList { uint blockList[]; };
// Per block: 4 frame + MESH_STAMP_* for the frame in which the block was last dirty (markBlockDirty). Raised with
// atomicMax, so the marks of one frame combine in any order and the strongest stays. (A uint: 2^30 frames, over
// 400 days at 30 frames a second.)
const uint MESH_STAMP_DIRTY = 0u;         // re-meshed (retype and claim)
const uint MESH_STAMP_READS_MOVED = 1u;   // ... and the vertices of its cubes that read a MOVES neighbour's corners move
const uint MESH_STAMP_MOVES = 2u;         // ... and all its vertices move (its own corners changed)
layout(std430, set = 0, binding = BINDING_MESH_STAMPS) coherent buffer MeshStamps { uint meshStamps[]; };
layout(std430, set = 0, binding = BINDING_DIRTY_LIST) buffer DirtyList { uint dirtyList[]; };
layout(std430, set = 0, binding = BINDING_RETYPE_MASK) coherent buffer RetypeMask { uint retypeMask[]; };
// The retype list (collect_retype): params.retypeCapacity cubes (block * 512 + local, NO_BLOCK for an entry left
// unused), then the list of those whose type changed, counters.cubesChanged pairs of the cube and the MC type
// mesh_claim classified it as (RETYPE_LIST_WORDS_PER_CUBE). mesh_triangulate runs over the changed cubes only and
// builds the listed type without classifying the cube again. On llvmpipe a lane whose cube keeps its type costs
// its 8-lane subgroup as much as one that changes (masked code runs), and ~60 % of the candidates keep theirs.
layout(std430, set = 0, binding = BINDING_RETYPE_LIST) buffer RetypeList { uint retypeList[]; };
void setChangedCube(uint k, uint id, uint type) {
    retypeList[params.retypeCapacity + 2u * k] = id;
    retypeList[params.retypeCapacity + 2u * k + 1u] = type;
}
// Reserves `count` entries of the changed-cube list, one atomic per subgroup (as reserveMovedVertices below).
uint reserveChangedCubes(uint count) {
    uint offset = subgroupExclusiveAdd(count);
    uint total = subgroupAdd(count);
    uint base = 0u;
    if (subgroupElect() && total != 0u) base = atomicAdd(counters.cubesChanged, total);
    return subgroupBroadcastFirst(base) + offset;
}
uvec2 changedCube(uint k) {   // (cube, new type)
    return uvec2(retypeList[params.retypeCapacity + 2u * k], retypeList[params.retypeCapacity + 2u * k + 1u]);
}
layout(std430, set = 0, binding = BINDING_GARBAGE) buffer Garbage { uint garbage[]; };
layout(std430, set = 0, binding = BINDING_MOVED_VERTICES) buffer MovedVertices { uint movedVertices[]; };
// Per block, NEIGHBORS_PER_BLOCK entries: the block index at each offset in {-1, 0, 1}^3 from it (NO_BLOCK when
// not allocated), written by cache_neighbors for every dirty block, and so valid for a block that is dirty this
// frame (blockDirty) (the hash does not change during the mesh passes). The mesh passes read a cube's
// neighbour blocks here instead of probing the hash up to 7 times per cube (26 with refinement; cubeRef,
// cube_access.glsl), and their pipelines need no hash buffers.
layout(std430, set = 0, binding = BINDING_BLOCK_NEIGHBORS) buffer BlockNeighbors { uint blockNeighbors[]; };

// With refinement (docs/REFINEMENT.md), per block MESH_SIGN_WORDS words (shared_layout.h), a group of 4 per mask
// word: the meshing signs (MESH_SIGN_MESHING, bit set when the corner is inside for meshing: decide_mesh_signs keeps
// them for every corner of the dirty blocks, before the retype list is collected; claim and triangulate type a cube
// from its 8 corners' bits), then the masks of the TSDF (MESH_SIGN_RAW, _NEAR, _OBSERVED) that fusion, recycling and
// map loading keep exact and decide_mesh_signs reads instead of the TSDF. Persistent: a corner's sign only changes
// when the TSDF within one corner of it does. Two views of one buffer: words, and a group as one uvec4 load (which
// on llvmpipe costs what a uint load does).
layout(std430, set = 0, binding = BINDING_MESH_SIGNS) coherent buffer MeshSigns { uint meshSigns[]; };
layout(std430, set = 0, binding = BINDING_MESH_SIGNS) coherent buffer MeshSignGroups { uvec4 meshSignGroups[]; };

// Per block MASK_WORDS words, bit `local`: the corner's sign or observed state flipped in fusion (fuse_depth), so
// the 8 cubes around it may change type. decide_mesh_signs marks them, word by word with shifts and the neighbour
// cache, and clears the word: fusion records a bit per corner (one atomic per subgroup and word) instead of
// marking 8 cubes per corner there, with up to 7 hash probes for a corner on a block's low faces (fusion
// 0.35 ms of ~4.5 on the synthetic room). Empty between frames.
layout(std430, set = 0, binding = BINDING_CORNER_FLIPS) coherent buffer CornerFlips { uint cornerFlips[]; };
// A word per allocation tile: 1 when allocate_tiles claimed the blocks of its slab, so allocate_blocks skips its
// pixels. Written for every tile each frame before allocate_blocks reads it.
layout(std430, set = 0, binding = BINDING_ALLOC_TILES) buffer AllocTiles { uint tileCovered[]; };

uint meshSignGroup(uint block, uint local) { return block * MASK_WORDS + local / 32u; }   // index into meshSignGroups
uint tsdfMaskWord(uint block, uint mask, uint local) { return block * MESH_SIGN_WORDS + MESH_SIGN_GROUP * (local / 32u) + mask; }


// The TSDF mask bits of one corner: bit 0 sdf < 0, bit 1 observed and |sdf| < refineEpsilon, bit 2 observed.
uint tsdfMaskBits(float sdf, float weight) {
    bool observed = weight >= params.minMeshWeight;
    return uint(sdf < 0.0) | (uint(observed && abs(sdf) < params.refineEpsilon) << 1) | (uint(observed) << 2);
}

// The bits of a workgroup-per-block pass's corners (fuse_depth, recycle_retire) packed into mask words. Invocation lid
// holds corners 4 lid .. 4 lid + 3 (cornerOfInvocation, block_store.glsl; VOXELS_PER_INVOCATION = 4), so its bits
// of one mask are a nibble at bit 4 (lid % 8) of word lid / 8. Where the subgroup is S consecutive invocations
// starting at a multiple of S (as on lavapipe, S = 8), it fills ceil(S / 8) words, one subgroupOr each (elsewhere
// each invocation writes its own nibble). Called by every invocation of the subgroup (uniform control flow).
bool subgroupPacksCorners() {
    uint lid = gl_LocalInvocationIndex, lo = subgroupMin(lid), hi = subgroupMax(lid);
    return hi - lo == gl_SubgroupSize - 1u && lo % gl_SubgroupSize == 0u;
}
uint cornerNibbleShift() { return 4u * (gl_LocalInvocationIndex % 8u); }
// Word w of the subgroup's words (subgroupPacksCorners): the nibbles of its invocations 8 w .. 8 w + 7.
uint subgroupCornerWord(uint nibble, uint w) {
    uint rel = gl_LocalInvocationIndex - subgroupMin(gl_LocalInvocationIndex);
    return subgroupOr(rel / 8u == w ? nibble << cornerNibbleShift() : 0u);
}
// The first corner of word w of the subgroup's words.
uint subgroupCornerWordStart(uint w) { return (subgroupMin(gl_LocalInvocationIndex) + 8u * w) * VOXELS_PER_INVOCATION; }
// Bit k of mask m of `bits`, where bit 3 k + m is mask m (raw, near, observed) of corner k.
uint cornerNibble(uint bits, uint m) {
    return ((bits >> m) & 1u) | ((bits >> (m + 2u)) & 2u) | ((bits >> (m + 4u)) & 4u) | ((bits >> (m + 6u)) & 8u);
}

// Toggles the TSDF mask bits that changed: `change` bit 3 k + m is mask m (raw, near, observed) of the invocation's
// corner k. One subgroupOr per mask and word, one atomicXor per changed word (3 and at most 3 for S = 8).
void toggleTsdfMasks(uint block, uint change) {
    if (subgroupPacksCorners()) {   // uniform over the subgroup
        uint words = (gl_SubgroupSize + 7u) / 8u;
        for (uint m = 0u; m < 3u; ++m) {
            uint nibble = cornerNibble(change, m);
            for (uint w = 0u; w < words; ++w) {
                uint v = subgroupCornerWord(nibble, w);
                if (v != 0u && subgroupElect()) atomicXor(meshSigns[tsdfMaskWord(block, MESH_SIGN_RAW + m, subgroupCornerWordStart(w))], v);
            }
        }
        return;
    }
    for (uint m = 0u; m < 3u; ++m) {
        uint nibble = cornerNibble(change, m);
        if (nibble != 0u) atomicXor(meshSigns[tsdfMaskWord(block, MESH_SIGN_RAW + m, gl_LocalInvocationIndex * VOXELS_PER_INVOCATION)], nibble << cornerNibbleShift());
    }
}

// Records the invocation's corners that flipped (`flipped` bit k: corner k) in the block's corner-flip words, packed
// as toggleTsdfMasks packs its bits: one subgroupOr and one atomicOr per word with a flip.
void recordCornerFlips(uint block, uint flipped) {
    if (subgroupPacksCorners()) {   // uniform over the subgroup
        uint words = (gl_SubgroupSize + 7u) / 8u;
        for (uint w = 0u; w < words; ++w) {
            uint v = subgroupCornerWord(flipped, w);
            if (v != 0u && subgroupElect()) atomicOr(cornerFlips[block * MASK_WORDS + subgroupCornerWordStart(w) / 32u], v);
        }
        return;
    }
    if (flipped != 0u) atomicOr(cornerFlips[block * MASK_WORDS + gl_LocalInvocationIndex * VOXELS_PER_INVOCATION / 32u], flipped << cornerNibbleShift());
}

// ---- dirty blocks -----------------------------------------------------------------------------------------
// A block is dirty when a cube of it may change type: its corners or, through its border cubes, a neighbour's
// changed. Its vertices move only when the corners their positions, normals and colours read changed: those of
// the edge's owner cube, i.e. the block (MESH_STAMP_MOVES) or, for the cubes on its upper faces, the blocks at +o,
// o in {0,1}^3 (MESH_STAMP_READS_MOVED: list_moved_vertices lists only the cubes on its upper faces, a third). With
// refinement the dirty blocks reach one block further (a corner's meshing sign reads the corners around it), and
// those extra blocks only retype: list_moved_vertices skips them (a third of the dirty blocks on the synthetic room).
bool blockDirty(uint block) { return (meshStamps[block] >> 2) == frame.frameNumber; }
bool blockMovesVertices(uint block) { return meshStamps[block] == 4u * frame.frameNumber + MESH_STAMP_MOVES; }
bool blockReadsMovedCorners(uint block) { return meshStamps[block] == 4u * frame.frameNumber + MESH_STAMP_READS_MOVED; }

// The mark a block at -offset of a block whose corners changed gets: offset 0 is the block itself; at o in
// {0,1}^3 it owns edges whose cubes read the changed corners; the other offsets (refinement) only retype. With
// recycling, corners of blocks that no pass marks change too (starving lowers an idle block's weights every frame,
// which moves its distances by a rounding, without a flip that would mark it), so there a block at o in {0,1}^3
// moves all its vertices, as before the upper-face rule (GpuTest.StarvationFreesIdleBlocksConsistently).
uint dirtyMarkAt(ivec3 offset) {
    bool recycling = params.keepRadius > 0.0 || params.starveAfterFrames != 0u;
    return offset == ivec3(0) ? MESH_STAMP_MOVES
         : all(greaterThanEqual(offset, ivec3(0))) ? (recycling ? MESH_STAMP_MOVES : MESH_STAMP_READS_MOVED) : MESH_STAMP_DIRTY;
}

// Appends a block to the dirty list and raises the dispatch over the list's mask words (cache_neighbors to
// collect_retype; from {0, 1, 1}: CounterBuffer::recordClearFrame) to cover it, so that no one-invocation pass has
// to size it after the marking.
void listDirtyBlock(uint block) {
    uint at = atomicAdd(counters.dirtyCount, 1u);
    dirtyList[at] = block;
    atomicMax(counters.collectDispatch[0], ((at + 1u) * MASK_WORDS + WG_LIST - 1u) / WG_LIST);
}

// Marks `block` dirty this frame with `how` (MESH_STAMP_*); the first to mark it lists it.
void markBlockDirty(uint block, uint how) {
    uint stamp = 4u * frame.frameNumber + how;
    if (meshStamps[block] >= stamp) return;   // already marked so (a plain read first: most marks repeat)
    if (atomicMax(meshStamps[block], stamp) < 4u * frame.frameNumber) listDirtyBlock(block);
}

uint neighborIndex(ivec3 offset) { return uint((offset.x + 1) + 3 * (offset.y + 1) + 9 * (offset.z + 1)); }
uint cachedNeighbor(uint block, ivec3 offset) { return blockNeighbors[block * NEIGHBORS_PER_BLOCK + neighborIndex(offset)]; }

// The two garbage lists (shared_layout.h, BINDING_GARBAGE).
uint gcCandidate(uint i) { return garbage[i]; }
void setGcCandidate(uint i, uint v) { garbage[i] = v; }
uint releasedChunk(uint i) { return garbage[params.vertexCapacity + i]; }
void setReleasedChunk(uint i, uint chunk) { garbage[params.vertexCapacity + i] = chunk; }

// Reserves `count` entries of the moved-vertex list for this invocation, one atomic per subgroup; returns
// the first. Called by every invocation of the subgroup (uniform control flow), with a count or 0. Entries
// at or past params.vertexCapacity do not exist (never more: each vertex is listed once). The same atomic
// subgroup raises move_vertices' dispatch (Counters::vertexDispatch, from 0 in commit_vertices) to cover them.
uint reserveMovedVertices(uint count) {
    uint offset = subgroupExclusiveAdd(count);
    uint total = subgroupAdd(count);
    uint base = 0u;
    if (subgroupElect() && total != 0u) {
        base = atomicAdd(counters.movedCount, total);
        atomicMax(counters.vertexDispatch[0], (min(base + total, params.vertexCapacity) + WG_LIST - 1u) / WG_LIST);
    }
    return subgroupBroadcastFirst(base) + offset;
}

// `slot`: the edge slot holding the vertex (move_vertices reads the vertex there).
void listMovedVertex(uint at, uint slot) {
    if (at < params.vertexCapacity) movedVertices[at] = slot;
}
#endif
