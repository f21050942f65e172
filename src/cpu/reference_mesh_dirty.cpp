// Dirty marking (docs/MESH.md; shaders_comp/mark_dirty/mark_dirty.comp, retype/collect_retype.comp, retype/plan_retype.comp): the
// dirty blocks D of a frame, the cubes of D that claim and triangulate re-evaluate (the GPU's retype list),
// and the (refined) type each of those cubes is to be built with.
#include "cpu/reference_mesh_internal.h"

#include <set>

#include "core/refinement.h"

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

std::vector<ReferenceMesher::DirtyBlock> ReferenceMesher::markDirty(const ReferenceVolume& volume,
                                                                    const std::vector<BlockCoord>& touched,
                                                                    RetypeScope scope, MeshFrameStats& stats) {
    // D: every touched block and every existing block T - o, o in {0,1}^3 (its cubes read corners in T).
    std::set<BlockCoord> dirtySet;
    for (const BlockCoord& t : touched) {
        for (int o = 0; o < kCubeCorners; ++o) {
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
                if (b.state->cubeState[cube] & gpu::CUBE_INCOMPLETE) b.retype.set(cube);
        }
        stats.cubesListed += uint32_t(b.retype.count());
    }
    return dirty;
}

// New type of every listed cube: t = MC type of its corners if all 8 exist with weight >= minMeshWeight,
// else 0; with refinement, refineType(stored type, t, d, epsilon). Computed before any cube state changes,
// so claim and triangulate see the same type.
void ReferenceMesher::chooseTypes(std::vector<DirtyBlock>& dirty) const {
    for (DirtyBlock& b : dirty) {
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            if (!b.retype.test(cube)) continue;
            const CubeCorners corners = readCorners(b.tsdf, cube, minMeshWeight_);
            int t = corners.observed ? cubeType(corners.d) : 0;
            if (options_.refine) t = refineType(int(b.state->cubeState[cube] & gpu::CUBE_TYPE_MASK), t, corners.d, refineEpsilon_);
            b.newType[cube] = uint8_t(t);
        }
    }
}

}  // namespace vkmesh::cpu
