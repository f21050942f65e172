#include "cpu/reference_mesher.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "core/marching_cubes.h"
#include "core/refinement.h"

namespace vkmesh::cpu {
namespace {

using gpu::BLOCK_SIDE;
using gpu::VOXELS_PER_BLOCK;

constexpr uint32_t kSlotsPerBlock = VOXELS_PER_BLOCK * 3;

std::array<int, 3> cubeCoords(uint32_t cube) {
    return {int(cube % BLOCK_SIDE), int((cube / BLOCK_SIDE) % BLOCK_SIDE), int(cube / (BLOCK_SIDE * BLOCK_SIDE))};
}

uint32_t cubeIndex(int x, int y, int z) { return uint32_t(x + int(BLOCK_SIDE) * (y + int(BLOCK_SIDE) * z)); }

BlockCoord plus(const BlockCoord& c, const std::array<int, 3>& o) { return {c[0] + o[0], c[1] + o[1], c[2] + o[2]}; }

// A point given in the local cube coordinates of a block, each in [0, 8]: which of the block's +x/+y/+z
// neighbourhood it falls into (numbered like cube corners: bit k set = one block further along axis k) and
// its cube index there.
struct Wrapped {
    int neighbour;
    uint32_t cube;
};
Wrapped wrap(const std::array<int, 3>& g) {
    const int side = int(BLOCK_SIDE);
    return {(g[0] / side) | ((g[1] / side) << 1) | ((g[2] / side) << 2),
            cubeIndex(g[0] % side, g[1] % side, g[2] % side)};
}

// A block and its 7 neighbours in +x, +y, +z, indexed like cube corners: everything a cube of the block reads.
std::array<const ReferenceBlock*, 8> tsdfNeighbourhood(const ReferenceVolume& volume, const BlockCoord& coord) {
    std::array<const ReferenceBlock*, 8> out{};
    for (int i = 0; i < 8; ++i) {
        auto it = volume.blocks().find(plus(coord, cornerOffset(i)));
        out[i] = it == volume.blocks().end() ? nullptr : &it->second;
    }
    return out;
}

// The 8 TSDF corners of one cube.
struct CubeCorners {
    float d[8] = {};
    bool exists[8] = {};   // the corner's block is allocated
    bool observed = true;  // all 8 exist and have weight >= minMeshWeight
};

CubeCorners readCorners(const std::array<const ReferenceBlock*, 8>& n, uint32_t cube, float minMeshWeight) {
    CubeCorners out;
    const auto local = cubeCoords(cube);
    for (int c = 0; c < 8; ++c) {
        const auto o = cornerOffset(c);
        const Wrapped w = wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
        const ReferenceBlock* block = n[w.neighbour];
        if (!block) {
            out.observed = false;
            continue;
        }
        out.exists[c] = true;
        out.d[c] = block->sdf[w.cube];
        if (block->weight[w.cube] < minMeshWeight) out.observed = false;
    }
    return out;
}

uint64_t globalEdgeId(const BlockMeshState& state, uint32_t cube, int axis) {
    return uint64_t(state.index) * kSlotsPerBlock + cube * 3 + uint32_t(axis);
}

// The lock-free claim passes (docs/REFINEMENT.md): pass k claims the cubes whose global position parity
// p = (x&1) | (y&1) << 1 | (z&1) << 2 is one of kParityPasses[k], i.e. (x&1, y&1, z&1) in {000, 111},
// {001, 110}, {010, 101}, {100, 011}: two parity vectors that differ on all three axes.
constexpr int kParityPasses[4][2] = {{0, 7}, {4, 3}, {2, 5}, {1, 6}};

int globalParity(const BlockCoord& block, uint32_t cube) {
    const auto l = cubeCoords(cube);
    const int side = int(BLOCK_SIDE);
    return ((block[0] * side + l[0]) & 1) | (((block[1] * side + l[1]) & 1) << 1) | (((block[2] * side + l[2]) & 1) << 2);
}

}  // namespace

// A block of D with everything its cubes read: the TSDF and the mesh state of it and its +x/+y/+z
// neighbours, and the new type of each of its cubes.
struct ReferenceMesher::DirtyBlock {
    BlockCoord coord{};
    BlockMeshState* state = nullptr;
    TsdfBlocks tsdf{};
    BlockMeshState* mesh[8] = {};
    CubeMask retype;                              // the cubes claim and triangulate visit
    std::array<uint8_t, VOXELS_PER_BLOCK> newType{};  // for those cubes: the (refined) type to build

    DirtyBlock(const ReferenceVolume& volume, std::map<BlockCoord, BlockMeshState>& states, const BlockCoord& c)
        : coord(c), state(&states.at(c)), tsdf(tsdfNeighbourhood(volume, c)) {
        for (int i = 0; i < 8; ++i) {
            auto it = states.find(plus(c, cornerOffset(i)));
            mesh[i] = it == states.end() ? nullptr : &it->second;
        }
    }

    // The slot of edge e of cube `cube`: it lives in the owner cube (this block or a +x/+y/+z neighbour).
    // Only called for cubes whose 8 corners exist, so the owner's block exists.
    struct Slot {
        BlockMeshState* state;
        uint32_t cube;
        int axis;
        uint32_t& vertex() const { return state->edgeVertex[cube * 3 + uint32_t(axis)]; }
    };
    Slot edgeSlot(uint32_t cube, int e) const {
        const auto local = cubeCoords(cube);
        const auto o = edgeOwnerOffset(e);
        const Wrapped w = wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
        if (!mesh[w.neighbour]) throw std::logic_error("ReferenceMesher: the owner block of an edge has no mesh state");
        return {mesh[w.neighbour], w.cube, edgeAxis(e)};
    }
};

ReferenceMesher::ReferenceMesher(const VolumeParams& params, float minMeshWeight, uint32_t vertexCapacity,
                                 uint32_t chunkCapacity, const MesherOptions& options)
    : params_(params),
      minMeshWeight_(minMeshWeight),
      options_(options),
      refineEpsilon_(options.refineEpsilon ? *options.refineEpsilon : defaultRefineEpsilon(params.voxelSize)),
      vertexCapacity_(vertexCapacity),
      chunkCapacity_(chunkCapacity) {
    if (vertexCapacity == 0 || chunkCapacity == 0) throw Error("ReferenceMesher: heap capacities must be positive");
    if (chunkCapacity > kMaxChunkCapacity)
        throw Error("ReferenceMesher: chunk capacity " + std::to_string(chunkCapacity) + " exceeds " +
                    std::to_string(kMaxChunkCapacity) + " (the chunk index + 1 must fit in 23 bits of a cube state)");
    MeshVertex dead;
    dead.refcount = kDead;
    vertices_.assign(vertexCapacity, dead);
    vertexOwner_.assign(vertexCapacity, ~uint64_t(0));
    chunkTriangles_.resize(chunkCapacity);
    for (auto& chunk : chunkTriangles_) chunk.fill(kInvalid);
    // Stacks with their top at the back: index 0 is popped first.
    freeVertices_.resize(vertexCapacity);
    for (uint32_t i = 0; i < vertexCapacity; ++i) freeVertices_[i] = vertexCapacity - 1 - i;
    freeChunks_.resize(chunkCapacity);
    for (uint32_t i = 0; i < chunkCapacity; ++i) freeChunks_[i] = chunkCapacity - 1 - i;
}

void ReferenceMesher::createBlockStates(const ReferenceVolume& volume) {
    for (const auto& [coord, block] : volume.blocks()) {
        auto [it, inserted] = blocks_.try_emplace(coord);
        if (!inserted) continue;
        BlockMeshState& state = it->second;
        state.cubeState.fill(0);
        state.edgeVertex.fill(kEmpty);
        state.coord = coord;
        state.index = uint32_t(blockByIndex_.size());
        blockByIndex_.push_back(&state);
    }
}

MeshFrameStats ReferenceMesher::updateAll(const ReferenceVolume& volume, uint32_t frameNumber) {
    std::vector<BlockCoord> all;
    all.reserve(volume.blocks().size());
    for (const auto& [coord, block] : volume.blocks()) all.push_back(coord);
    return update(volume, all, frameNumber, RetypeScope::AllCubes);
}

MeshFrameStats ReferenceMesher::update(const ReferenceVolume& volume, const std::vector<BlockCoord>& touched,
                                       uint32_t frameNumber, RetypeScope scope) {
    if (scope == RetypeScope::FlippedCorners) {
        if (volume.minMeshWeight() != minMeshWeight_)
            throw Error("ReferenceMesher: the volume flags corners at minMeshWeight " +
                        std::to_string(volume.minMeshWeight()) + ", the mesher meshes at " + std::to_string(minMeshWeight_));
        if (options_.refine && (!volume.refinement() || volume.refineEpsilon() != refineEpsilon_))
            throw Error("ReferenceMesher: refinement is on (epsilon " + std::to_string(refineEpsilon_) +
                        " m) but the volume does not flag corners crossing that epsilon (ReferenceVolume::setRefinement)");
    }
    MeshFrameStats stats;
    createBlockStates(volume);
    gcCandidates_.clear();
    releasedChunks_.clear();
    newVertices_.clear();

    // D: every touched block and every existing block T - o, o in {0,1}^3 (its cubes read corners in T).
    std::set<BlockCoord> dirtySet;
    for (const BlockCoord& t : touched) {
        for (int o = 0; o < 8; ++o) {
            const auto off = cornerOffset(o);
            const BlockCoord c{t[0] - off[0], t[1] - off[1], t[2] - off[2]};
            if (volume.blocks().count(c)) dirtySet.insert(c);
        }
    }
    std::vector<DirtyBlock> dirty;
    dirty.reserve(dirtySet.size());
    for (const BlockCoord& c : dirtySet) dirty.emplace_back(volume, blocks_, c);
    stats.dirtyBlocks = uint32_t(dirty.size());

    // The cubes to re-evaluate (the GPU's retype list): all of D, or the cubes around the corners the last
    // integrate() flipped and the INCOMPLETE cubes (the GPU sets their retype bit again). The other cubes of D
    // keep their type: without a flipped corner neither their MC type nor their refined type can change.
    for (DirtyBlock& b : dirty) {
        if (scope == RetypeScope::AllCubes) {
            b.retype.set();
        } else {
            auto it = volume.retypeCubes().find(b.coord);
            if (it != volume.retypeCubes().end()) b.retype = it->second;
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
                if (b.state->cubeState[cube] & kIncomplete) b.retype.set(cube);
        }
        stats.cubesListed += uint32_t(b.retype.count());
    }

    // New type of every listed cube: t = MC type of its corners if all 8 exist with weight >= minMeshWeight,
    // else 0; with refinement, refineType(stored type, t, d, epsilon). Computed before any cube state changes,
    // so claim and triangulate see the same type.
    for (DirtyBlock& b : dirty) {
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            if (!b.retype.test(cube)) continue;
            const CubeCorners corners = readCorners(b.tsdf, cube, minMeshWeight_);
            int t = corners.observed ? cubeType(corners.d) : 0;
            if (options_.refine) t = refineType(int(b.state->cubeState[cube] & kTypeMask), t, corners.d, refineEpsilon_);
            b.newType[cube] = uint8_t(t);
        }
    }

    // 1. Claim: block by block (the default order), or in the 4 parity passes of the lock-free variant, each
    // over all of D. Within one lock-free pass no two cubes may look at the same edge slot (counted).
    if (!options_.lockFree) {
        for (DirtyBlock& b : dirty)
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
                if (b.retype.test(cube)) claimCube(b, cube, stats, frameNumber);
    } else {
        const MarchingCubesTables& tables = marchingCubesTables();
        for (const auto& pass : kParityPasses) {
            std::set<uint64_t> slotsSeen;  // (owner block index, cube, axis) of the slots this pass looked at
            for (DirtyBlock& b : dirty) {
                for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
                    if (!b.retype.test(cube)) continue;
                    const int parity = globalParity(b.coord, cube);
                    if (parity != pass[0] && parity != pass[1]) continue;
                    const uint32_t mask = tables.edgeMask[b.newType[cube]];
                    for (int e = 0; e < kCubeEdges; ++e) {
                        if (!((mask >> e) & 1)) continue;
                        const DirtyBlock::Slot slot = b.edgeSlot(cube, e);
                        if (!slotsSeen.insert(globalEdgeId(*slot.state, slot.cube, slot.axis)).second)
                            ++stats.lockFreeSharedSlots;
                    }
                    claimCube(b, cube, stats, frameNumber);
                }
            }
        }
    }

    // 2. Update: every live vertex whose owner block is in D (every owned slot of D's cubes that holds one) ...
    for (DirtyBlock& b : dirty)
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
            for (int axis = 0; axis < 3; ++axis)
                if (b.state->edgeVertex[cube * 3 + uint32_t(axis)] != kEmpty) updateVertex(b.tsdf, *b.state, cube, axis);
    // ... and every vertex claimed this frame whose owner block is not in D (docs/MESH.md; needed for
    // incremental == from scratch). A cube of block B in D can need an edge lying wholly in B + o, o != 0,
    // while B + o is outside D: e.g. the cube's corners in B just reached minMeshWeight (or B was just
    // allocated) and no other cube used that edge before. The pass over D alone would leave the new vertex
    // without a position (6 vertices in the room test's 10 frames).
    for (uint32_t v : newVertices_) {
        const BlockMeshState& owner = *blockByIndex_[vertexOwner_[v] / kSlotsPerBlock];
        if (dirtySet.count(owner.coord)) continue;
        const uint32_t slot = uint32_t(vertexOwner_[v] % kSlotsPerBlock);
        updateVertex(tsdfNeighbourhood(volume, owner.coord), owner, slot / 3, int(slot % 3));
        ++stats.newVerticesOutsideDirty;
    }

    // 3. Triangulate.
    for (DirtyBlock& b : dirty) triangulate(b, stats);

    // 4. Collect garbage.
    collectGarbage(stats);
    return stats;
}

// Claim (docs/MESH.md, pass 1) for one cube: every edge of its new type without a vertex gets one from the heap.
void ReferenceMesher::claimCube(DirtyBlock& b, uint32_t cube, MeshFrameStats& stats, uint32_t frameNumber) {
    const uint32_t mask = marchingCubesTables().edgeMask[b.newType[cube]];
    for (int e = 0; e < kCubeEdges; ++e) {
        if (!((mask >> e) & 1)) continue;
        const DirtyBlock::Slot slot = b.edgeSlot(cube, e);
        if (slot.vertex() != kEmpty) continue;
        if (freeVertices_.empty()) {  // the slot stays EMPTY; triangles on it become INVALID
            ++stats.vertexExhausted;
            continue;
        }
        const uint32_t v = freeVertices_.back();
        freeVertices_.pop_back();
        vertexHighWater_ = std::max(vertexHighWater_, liveVertices());
        MeshVertex& vertex = vertices_[v];
        vertex = MeshVertex{};
        vertex.refcount = 0;
        vertex.createdFrame = frameNumber;
        vertexOwner_[v] = globalEdgeId(*slot.state, slot.cube, slot.axis);
        slot.vertex() = v;
        newVertices_.push_back(v);
        gcCandidates_.push_back(v);  // freed at the end of the frame if no triangle takes it
        ++stats.verticesAllocated;
    }
}

// Position and normal of the vertex in the slot (owner cube `cube` of block `owner`, `axis`), from the owner
// cube's corners: corner 0 is the edge's low end, corner 1 << axis its high end.
void ReferenceMesher::updateVertex(const TsdfBlocks& tsdf, const BlockMeshState& owner, uint32_t cube, int axis) {
    MeshVertex& vertex = vertices_[owner.edgeVertex[cube * 3 + uint32_t(axis)]];
    const CubeCorners corners = readCorners(tsdf, cube, minMeshWeight_);
    const int hi = 1 << axis;
    const float dLo = corners.d[0], dHi = corners.d[hi];
    if (!corners.exists[0] || !corners.exists[hi] || dLo == dHi) return;  // keeps its position

    // Exactly the float operations of ReferenceVolume::extractBaselineMesh, s clamped to [-0.5, 1.5]: an edge
    // of a refined type whose corners have the same sign gets an extrapolated vertex (docs/REFINEMENT.md);
    // where they differ in sign s is in (0, 1] and the clamp changes nothing.
    const float s = std::clamp(dLo / (dLo - dHi), -0.5f, 1.5f);
    const auto local = cubeCoords(cube);
    float p[3] = {float(owner.coord[0] * 8 + local[0]), float(owner.coord[1] * 8 + local[1]),
                  float(owner.coord[2] * 8 + local[2])};
    p[axis] += s;
    vertex.px = p[0] * params_.voxelSize;
    vertex.py = p[1] * params_.voxelSize;
    vertex.pz = p[2] * params_.voxelSize;

    // Normal: the owner cube's gradient g_a = (sum of d over corners with bit a) - (sum over the others),
    // accumulated in corner order as g_a += (bit a of c ? d_c : -d_c) (the order of mesh_triangulate.comp),
    // normalised as g / |g|; the edge axis, pointing to the larger d, when a corner is missing or g is zero.
    float n[3] = {0.0f, 0.0f, 0.0f};
    n[axis] = dHi - dLo >= 0.0f ? 1.0f : -1.0f;
    if (std::all_of(std::begin(corners.exists), std::end(corners.exists), [](bool e) { return e; })) {
        float g[3] = {0.0f, 0.0f, 0.0f};
        for (int c = 0; c < 8; ++c)
            for (int a = 0; a < 3; ++a) g[a] += ((c >> a) & 1) ? corners.d[c] : -corners.d[c];
        const float length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (length > 0.0f)
            for (int a = 0; a < 3; ++a) n[a] = g[a] / length;
    }
    vertex.nx = n[0];
    vertex.ny = n[1];
    vertex.nz = n[2];
}

void ReferenceMesher::releaseReference(uint32_t v) {
    MeshVertex& vertex = vertices_.at(v);
    if (vertex.refcount == 0 || vertex.refcount == kDead)
        throw std::logic_error("ReferenceMesher: releasing a triangle of a vertex without references");
    if (--vertex.refcount == 0) gcCandidates_.push_back(v);
}

void ReferenceMesher::triangulate(DirtyBlock& b, MeshFrameStats& stats) {
    const MarchingCubesTables& tables = marchingCubesTables();
    for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
        if (!b.retype.test(cube)) continue;
        const uint32_t state = b.state->cubeState[cube];
        const uint32_t oldType = state & kTypeMask;
        const uint32_t newType = b.newType[cube];
        if (newType == oldType && !(state & kIncomplete)) continue;  // temporal consistency: keep the triangles
        ++stats.cubesRetyped;

        uint32_t chunk = state >> kChunkShift;  // chunk index + 1, 0 = none
        if (chunk) {                           // release every existing triangle
            auto& tris = chunkTriangles_[chunk - 1];
            for (int k = 0; k < kChunkTriangles; ++k) {
                if (tris[3 * k] == kInvalid) continue;
                for (int j = 0; j < 3; ++j) releaseReference(tris[3 * k + j]);
                tris[3 * k] = tris[3 * k + 1] = tris[3 * k + 2] = kInvalid;
                ++stats.trianglesReleased;
            }
        }

        uint32_t newState = newType;
        const int count = tables.triangleCount[newType];
        if (count == 0) {
            if (chunk) releasedChunks_.push_back(chunk - 1);
            chunk = 0;
        } else {
            if (!chunk) {
                if (freeChunks_.empty()) {
                    ++stats.chunkExhausted;
                    stats.trianglesInvalid += uint32_t(count);
                    newState |= kIncomplete;
                } else {
                    chunk = freeChunks_.back() + 1;
                    freeChunks_.pop_back();
                    chunkHighWater_ = std::max(chunkHighWater_, liveChunks());
                    ++stats.chunksAllocated;
                }
            }
            if (chunk) {
                auto& tris = chunkTriangles_[chunk - 1];
                for (int k = 0; k < count; ++k) {
                    uint32_t v[3];
                    bool valid = true;
                    for (int j = 0; j < 3; ++j) {
                        v[j] = b.edgeSlot(cube, tables.triangleEdges[newType][3 * k + j]).vertex();
                        if (v[j] == kEmpty) valid = false;
                    }
                    if (!valid) {
                        ++stats.trianglesInvalid;
                        newState |= kIncomplete;
                        continue;
                    }
                    for (int j = 0; j < 3; ++j) {
                        tris[3 * k + j] = v[j];
                        ++vertices_[v[j]].refcount;
                    }
                    ++stats.trianglesCreated;
                }
            }
        }
        b.state->cubeState[cube] = newState | (chunk << kChunkShift);
    }
}

void ReferenceMesher::collectGarbage(MeshFrameStats& stats) {
    for (uint32_t v : gcCandidates_) {
        MeshVertex& vertex = vertices_[v];
        if (vertex.refcount != 0) continue;  // taken again, or already freed (a vertex can be a candidate twice)
        vertex.refcount = kDead;
        BlockMeshState& owner = *blockByIndex_[vertexOwner_[v] / kSlotsPerBlock];
        owner.edgeVertex[vertexOwner_[v] % kSlotsPerBlock] = kEmpty;
        vertexOwner_[v] = ~uint64_t(0);
        freeVertices_.push_back(v);
        ++stats.verticesFreed;
    }
    for (uint32_t c : releasedChunks_) {
        freeChunks_.push_back(c);
        ++stats.chunksFreed;
    }
    gcCandidates_.clear();
    releasedChunks_.clear();
}

uint32_t ReferenceMesher::incompleteCubes() const {
    uint32_t count = 0;
    for (const auto& [coord, state] : blocks_)
        for (uint32_t cubeState : state.cubeState)
            if (cubeState & kIncomplete) ++count;
    return count;
}

Mesh ReferenceMesher::exportMesh(uint32_t currentFrame) const {
    Mesh mesh;
    std::vector<uint32_t> dense(vertexCapacity_, kInvalid);
    for (uint32_t v = 0; v < vertexCapacity_; ++v) {
        const MeshVertex& vertex = vertices_[v];
        if (vertex.refcount == kDead || vertex.refcount == 0) continue;
        dense[v] = uint32_t(mesh.positions.size());
        mesh.positions.emplace_back(vertex.px, vertex.py, vertex.pz);
        mesh.normals.emplace_back(vertex.nx, vertex.ny, vertex.nz);
        mesh.vertexAge.push_back(currentFrame - vertex.createdFrame);
    }
    for (const auto& [coord, state] : blocks_) {
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            const uint32_t chunk = state.cubeState[cube] >> kChunkShift;
            if (!chunk) continue;
            const auto& tris = chunkTriangles_[chunk - 1];
            for (int k = 0; k < kChunkTriangles; ++k)
                if (tris[3 * k] != kInvalid)
                    mesh.triangles.push_back({dense[tris[3 * k]], dense[tris[3 * k + 1]], dense[tris[3 * k + 2]]});
        }
    }
    return mesh;
}

std::vector<std::string> ReferenceMesher::checkInvariants() const {
    const MarchingCubesTables& tables = marchingCubesTables();
    std::vector<std::string> problems;
    size_t total = 0;
    auto report = [&](const std::string& what) {
        if (++total <= 20) problems.push_back(what);
    };
    auto where = [](const BlockCoord& c, uint32_t cube) {
        const auto l = cubeCoords(cube);
        return "block (" + std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) +
               ") cube (" + std::to_string(l[0]) + "," + std::to_string(l[1]) + "," + std::to_string(l[2]) + ")";
    };
    auto live = [&](uint32_t v) { return v < vertexCapacity_ && vertices_[v].refcount != kDead; };

    std::vector<uint32_t> references(vertexCapacity_, 0);
    std::vector<uint32_t> chunkUsers(chunkCapacity_, 0);
    for (const auto& [coord, state] : blocks_) {
        // The +x/+y/+z neighbours' states, for the slots of a complete cube's triangles.
        const BlockMeshState* mesh[8];
        for (int i = 0; i < 8; ++i) {
            auto it = blocks_.find(plus(coord, cornerOffset(i)));
            mesh[i] = it == blocks_.end() ? nullptr : &it->second;
        }
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            for (int axis = 0; axis < 3; ++axis) {
                const uint32_t v = state.edgeVertex[cube * 3 + uint32_t(axis)];
                if (v == kEmpty) continue;
                if (!live(v)) report(where(coord, cube) + ": slot " + std::to_string(axis) + " holds a dead vertex " + std::to_string(v));
                else if (vertexOwner_[v] != globalEdgeId(state, cube, axis))
                    report(where(coord, cube) + ": slot " + std::to_string(axis) + " holds vertex " + std::to_string(v) + " owned elsewhere");
            }
            const uint32_t cubeState = state.cubeState[cube];
            const uint32_t type = cubeState & kTypeMask;
            const uint32_t chunk = cubeState >> kChunkShift;
            const int count = tables.triangleCount[type];
            if (chunk > chunkCapacity_) {
                report(where(coord, cube) + ": chunk index out of range");
                continue;
            }
            if (chunk) {
                ++chunkUsers[chunk - 1];
                if (count == 0) report(where(coord, cube) + ": holds a chunk but its type has no triangles");
                const auto& tris = chunkTriangles_[chunk - 1];
                for (int k = 0; k < kChunkTriangles; ++k) {
                    if (tris[3 * k] == kInvalid) continue;
                    for (int j = 0; j < 3; ++j) {
                        const uint32_t v = tris[3 * k + j];
                        if (!live(v)) report(where(coord, cube) + ": triangle uses a dead vertex " + std::to_string(v));
                        else ++references[v];
                    }
                }
            }
            if (cubeState & kIncomplete) continue;
            if (count > 0 && !chunk) {
                report(where(coord, cube) + ": complete with triangles but no chunk");
                continue;
            }
            if (!chunk) continue;
            // A complete cube's chunk holds exactly its type's triangles on its current edge vertices.
            const auto& tris = chunkTriangles_[chunk - 1];
            const auto local = cubeCoords(cube);
            for (int k = 0; k < kChunkTriangles; ++k) {
                for (int j = 0; j < 3; ++j) {
                    uint32_t expected = kInvalid;
                    if (k < count) {
                        const int e = tables.triangleEdges[type][3 * k + j];
                        const auto o = edgeOwnerOffset(e);
                        const Wrapped w = wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
                        expected = mesh[w.neighbour] ? mesh[w.neighbour]->edgeVertex[w.cube * 3 + uint32_t(edgeAxis(e))] : kEmpty;
                    }
                    if (k >= count && j > 0) break;  // only the first index marks a missing triangle
                    if (tris[3 * k + j] != expected) {
                        report(where(coord, cube) + ": triangle " + std::to_string(k) + " is not its type's triangle on the current edge vertices");
                        break;
                    }
                }
            }
        }
    }

    uint32_t liveCount = 0;
    for (uint32_t v = 0; v < vertexCapacity_; ++v) {
        const MeshVertex& vertex = vertices_[v];
        if (vertex.refcount == kDead) continue;
        ++liveCount;
        if (vertex.refcount == 0) report("vertex " + std::to_string(v) + " is live without triangles");
        if (vertex.refcount != references[v])
            report("vertex " + std::to_string(v) + ": refcount " + std::to_string(vertex.refcount) + " but " +
                   std::to_string(references[v]) + " live triangles use it");
        const uint64_t owner = vertexOwner_[v];
        if (owner / kSlotsPerBlock >= blockByIndex_.size() ||
            blockByIndex_[owner / kSlotsPerBlock]->edgeVertex[owner % kSlotsPerBlock] != v)
            report("vertex " + std::to_string(v) + ": its owner slot does not point back to it");
    }
    std::vector<char> onStack(vertexCapacity_, 0);
    for (uint32_t v : freeVertices_) {
        if (v >= vertexCapacity_ || onStack[v]) report("free vertex stack: entry " + std::to_string(v) + " out of range or repeated");
        else if (vertices_[v].refcount != kDead) report("free vertex stack: vertex " + std::to_string(v) + " is live");
        if (v < vertexCapacity_) onStack[v] = 1;
    }
    if (size_t(liveCount) + freeVertices_.size() != vertexCapacity_)
        report("vertex heap: " + std::to_string(liveCount) + " live + " + std::to_string(freeVertices_.size()) +
               " free != capacity " + std::to_string(vertexCapacity_));

    uint32_t usedChunks = 0;
    for (uint32_t c = 0; c < chunkCapacity_; ++c) {
        if (chunkUsers[c] > 1) report("chunk " + std::to_string(c) + " belongs to " + std::to_string(chunkUsers[c]) + " cubes");
        if (chunkUsers[c]) ++usedChunks;
    }
    std::vector<char> chunkOnStack(chunkCapacity_, 0);
    for (uint32_t c : freeChunks_) {
        if (c >= chunkCapacity_ || chunkOnStack[c]) report("free chunk stack: entry " + std::to_string(c) + " out of range or repeated");
        else if (chunkUsers[c]) report("free chunk stack: chunk " + std::to_string(c) + " belongs to a cube");
        if (c < chunkCapacity_) chunkOnStack[c] = 1;
    }
    if (size_t(usedChunks) + freeChunks_.size() != chunkCapacity_)
        report("chunk heap: " + std::to_string(usedChunks) + " live + " + std::to_string(freeChunks_.size()) +
               " free != capacity " + std::to_string(chunkCapacity_));

    if (total > problems.size()) problems.push_back("... and " + std::to_string(total - problems.size()) + " more");
    return problems;
}

}  // namespace vkmesh::cpu
