// Dirty marking (docs/MESH.md; shaders_comp/mark_dirty/mark_dirty.comp, retype/collect_retype.comp): the
// dirty blocks D of a frame, the cubes of D that claim and triangulate re-evaluate (the GPU's retype list),
// and the (refined) type each of those cubes is to be built with.
#include "cpu/reference_mesh_internal.h"

#include <cmath>
#include <set>

#include "core/refinement.h"

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

namespace {

// The TSDF corner at global grid position (x, y, z), from whichever block holds it: its value and whether it is
// observed (its block exists and its weight is at least minMeshWeight). Absent: d = 0, not observed.
void readVolumeCorner(const ReferenceVolume& volume, float minMeshWeight, int x, int y, int z, float& d, bool& observed) {
    const int side = int(gpu::BLOCK_SIDE);
    const BlockCoord c{blockOf(x), blockOf(y), blockOf(z)};
    auto it = volume.blocks().find(c);
    d = 0.0f;
    observed = false;
    if (it == volume.blocks().end()) return;
    const uint32_t v = localIndex(x - c[0] * side, y - c[1] * side, z - c[2] * side);
    d = it->second.sdf[v];
    observed = it->second.weight[v] >= minMeshWeight;
}

// Whether the 8 corners of the cube at global grid position (x, y, z) (its corner 0) are all observed.
bool cubeObservedAt(const ReferenceVolume& volume, float minMeshWeight, int x, int y, int z) {
    for (int o = 0; o < 8; ++o) {
        float d = 0.0f;
        bool observed = false;
        readVolumeCorner(volume, minMeshWeight, x + (o & 1), y + ((o >> 1) & 1), z + ((o >> 2) & 1), d, observed);
        if (!observed) return false;
    }
    return true;
}

}  // namespace

std::vector<ReferenceMesher::DirtyBlock> ReferenceMesher::markDirty(const ReferenceVolume& volume,
                                                                    const std::vector<BlockCoord>& touched,
                                                                    RetypeScope scope, MeshFrameStats& stats) {
    // D: every touched block and every existing block T - o, o in {0,1}^3 (its cubes read corners in T); with
    // refinement T + o, o in {-1,0,1}^3, since a flipped corner's marks reach a block ahead (mark_dirty.comp).
    std::set<BlockCoord> dirtySet;
    const int offsets = options_.refine ? 27 : kCubeCorners;
    for (const BlockCoord& t : touched) {
        for (int o = 0; o < offsets; ++o) {
            const std::array<int, 3> off = options_.refine ? std::array<int, 3>{o % 3 - 1, (o / 3) % 3 - 1, o / 9 - 1} : cornerOffset(o);
            const BlockCoord c{t[0] - off[0], t[1] - off[1], t[2] - off[2]};
            if (volume.blocks().count(c)) dirtySet.insert(c);
        }
    }
    std::vector<DirtyBlock> dirty;
    dirty.reserve(dirtySet.size());
    for (const BlockCoord& c : dirtySet) dirty.emplace_back(volume, blocks_, c);
    stats.dirtyBlocks = uint32_t(dirty.size());

    // The cubes to re-evaluate (the GPU's retype list): all of D, or the cubes around the corners the last
    // integrate() flipped (with refinement: around those whose observed state flipped and around those whose meshing
    // sign changed, where that can change the cube's type), and the INCOMPLETE cubes (the GPU sets their retype bit
    // again). The other cubes of D keep their type: with none of their corners changed neither their MC type nor
    // their refined type can change. With refinement a cube with a corner unobserved has type 0, as has one whose
    // corners are all outside: an observed flip alone (its corner's meshing sign unchanged) changes a type only where
    // the cube has a corner that may be inside for meshing (raw sign inside, or near), and where the last call only
    // added weight (no de-integration, no recycling) neither kind of change alters a cube with a corner unobserved
    // now, which had one before too (decide_mesh_signs.comp, cubeWindow).
    std::vector<CubeMask> observedFlips(dirty.size());
    for (size_t i = 0; i < dirty.size(); ++i) {
        DirtyBlock& b = dirty[i];
        if (scope == RetypeScope::AllCubes) {
            b.retype.set();
        } else {
            const auto& marked = options_.refine ? volume.observedRetypeCubes() : volume.retypeCubes();
            auto it = marked.find(b.coord);
            if (it != marked.end()) (options_.refine ? observedFlips[i] : b.retype) = it->second;
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
                if (b.state->cubeState[cube] & gpu::CUBE_INCOMPLETE) b.retype.set(cube);
        }
    }
    if (options_.refine) {
        const std::set<std::array<int, 3>> signChanged = decideMeshSigns(volume, dirty);
        // The corners whose observed state alone flipped (not their meshing sign): the cubes around them are listed
        // where they have a corner that may be inside (and, where the call only added weight, all corners observed;
        // those around a sign change: decideMeshSigns).
        std::set<std::array<int, 3>> observedOnly;
        for (const auto& c : volume.lastObservedFlipped())
            if (!signChanged.count(c)) observedOnly.insert(c);
        const int side = int(gpu::BLOCK_SIDE);
        // A corner that may be inside for meshing: its raw sign is, or it is near (only a near corner's meshing sign
        // differs from its raw one): the GPU's masks of the TSDF, which no sign decision changes.
        auto mayBeInside = [&](int x, int y, int z) {
            float d = 0.0f;
            bool observed = false;
            readVolumeCorner(volume, minMeshWeight_, x, y, z, d, observed);
            return d < 0.0f || (observed && std::fabs(d) < refineEpsilon_);
        };
        for (size_t i = 0; i < dirty.size(); ++i) {
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
                if (!observedFlips[i].test(cube) || dirty[i].retype.test(cube)) continue;
                const auto l = localCoords(cube);
                const BlockCoord& c = dirty[i].coord;
                const int x = c[0] * side + int(l[0]), y = c[1] * side + int(l[1]), z = c[2] * side + int(l[2]);
                bool inside = false, aroundObservedOnly = false;
                for (int o = 0; o < kCubeCorners; ++o) {
                    const auto off = cornerOffset(o);
                    inside = inside || mayBeInside(x + off[0], y + off[1], z + off[2]);
                    aroundObservedOnly = aroundObservedOnly || observedOnly.count({x + off[0], y + off[1], z + off[2]}) != 0;
                }
                const bool observed = volume.lastMayLoseObservations() || cubeObservedAt(volume, minMeshWeight_, x, y, z);
                if (inside && aroundObservedOnly && observed) dirty[i].retype.set(cube);
            }
        }
    }
    for (const DirtyBlock& b : dirty) stats.cubesListed += uint32_t(b.retype.count());
    return dirty;
}

// The meshing signs (decide_mesh_signs.comp, which decides every corner of D from the masks of the TSDF): every
// corner of D gets refinedCornerInside() of its 3x3x3 window; where that differs from the stored sign, the sign
// is stored and the 8 cubes around the corner (corner - o, o in {0,1}^3) are listed, where the last call only added
// weight only those whose corners are all observed (markDirty). Those lie in D: a sign only changes with the TSDF within one corner of it, D holds every block
// within one block of a touched one, and every block is in D the frame it is created. (A mark outside D, which
// would need a sign decided before its window's last change, the GPU keeps for a later frame; here it has
// none to keep.)
std::set<std::array<int, 3>> ReferenceMesher::decideMeshSigns(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty) const {
    const int side = int(gpu::BLOCK_SIDE);
    std::set<std::array<int, 3>> changed;
    std::map<BlockCoord, DirtyBlock*> byCoord;
    for (DirtyBlock& b : dirty) byCoord[b.coord] = &b;
    for (DirtyBlock& b : dirty) {
        for (uint32_t local = 0; local < VOXELS_PER_BLOCK; ++local) {
            const auto l = localCoords(local);
            const int g[3] = {b.coord[0] * side + int(l[0]), b.coord[1] * side + int(l[1]), b.coord[2] * side + int(l[2])};
            float d[kCornerWindowSize];
            bool observed[kCornerWindowSize];
            for (int w = 0; w < kCornerWindowSize; ++w)
                readVolumeCorner(volume, minMeshWeight_, g[0] + w % 3 - 1, g[1] + (w / 3) % 3 - 1, g[2] + w / 9 - 1, d[w], observed[w]);
            const bool inside = refinedCornerInside(d, observed, refineEpsilon_);
            if (inside == b.state->meshInside.test(local)) continue;
            b.state->meshInside.flip(local);
            changed.insert({g[0], g[1], g[2]});
            for (int o = 0; o < 8; ++o) {
                const int x = g[0] - (o & 1), y = g[1] - ((o >> 1) & 1), z = g[2] - ((o >> 2) & 1);
                auto it = byCoord.find(BlockCoord{blockOf(x), blockOf(y), blockOf(z)});
                if (it == byCoord.end()) continue;
                if (!volume.lastMayLoseObservations() && !cubeObservedAt(volume, minMeshWeight_, x, y, z)) continue;   // type 0 before and after
                const BlockCoord& c = it->first;
                it->second->retype.set(localIndex(x - c[0] * side, y - c[1] * side, z - c[2] * side));
            }
        }
    }
    return changed;
}

// New type of every listed cube: t = MC type of its corners if all 8 exist with weight >= minMeshWeight,
// else 0; with refinement, refinedCubeType() of the 4x4x4 corners around it (docs/REFINEMENT.md). Computed
// before any cube state changes, so claim and triangulate see the same type.
void ReferenceMesher::chooseTypes(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty) const {
    const int side = int(gpu::BLOCK_SIDE);
    for (DirtyBlock& b : dirty) {
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            if (!b.retype.test(cube)) continue;
            int t = 0;
            if (options_.refine) {
                // The window, read from whichever blocks hold it: the pure function of the TSDF, against which the
                // stored signs (and the GPU's, which claim and triangulate read) are checked.
                float d[kWindowSize];
                bool observed[kWindowSize];
                const auto l = localCoords(cube);
                for (int w = 0; w < kWindowSize; ++w)
                    readVolumeCorner(volume, minMeshWeight_, b.coord[0] * side + l[0] + w % 4 - 1, b.coord[1] * side + l[1] + (w / 4) % 4 - 1,
                                     b.coord[2] * side + l[2] + w / 16 - 1, d[w], observed[w]);
                t = refinedCubeType(d, observed, refineEpsilon_);
            } else {
                const CubeCorners corners = readCorners(b.tsdf, cube, minMeshWeight_);
                t = corners.observed ? cubeType(corners.d) : 0;
            }
            b.newType[cube] = uint8_t(t);
        }
    }
}

}  // namespace vkmesh::cpu
