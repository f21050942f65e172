// Vertex update (docs/MESH.md, pass 2; shaders_comp/update_*vertices.comp): positions and normals of the
// vertices the dirty blocks own and of those claimed this frame, with the baseline's float operations, and
// their colours.
#include "cpu/reference_mesh_internal.h"

#include "core/refinement.h"
#include "core/voxel_color.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

// Every live vertex whose owner block is in D (every owned slot of D's cubes that holds one) ... and every
// vertex claimed this frame whose owner block is not in D (docs/MESH.md; needed for incremental == from
// scratch). A cube of block B in D can need an edge lying wholly in B + o, o != 0, while B + o is outside D:
// e.g. the cube's corners in B just reached minMeshWeight (or B was just allocated) and no other cube used
// that edge before. The pass over D alone would leave the new vertex without a position (6 vertices in the
// room test's 10 frames).
void ReferenceMesher::updateVertices(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty, MeshFrameStats& stats) {
    std::set<BlockCoord> dirtySet;
    for (DirtyBlock& b : dirty) {
        dirtySet.insert(b.coord);
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
            for (int axis = 0; axis < 3; ++axis)
                if (b.state->edgeVertex[cube * 3 + uint32_t(axis)] != gpu::EMPTY_SLOT) updateVertex(b.tsdf, *b.state, cube, axis);
    }
    for (uint32_t v : newVertices_) {
        const BlockMeshState& owner = *blockByIndex_[vertexOwner_[v] / SLOTS_PER_BLOCK];
        if (dirtySet.count(owner.coord)) continue;
        const uint32_t slot = uint32_t(vertexOwner_[v] % SLOTS_PER_BLOCK);
        updateVertex(tsdfNeighbourhood(volume, owner.coord), owner, slot / 3, int(slot % 3));
        ++stats.newVerticesOutsideDirty;
    }
}

// Position and normal of the vertex in the slot (owner cube `cube` of block `owner`, `axis`), from the owner
// cube's corners: corner 0 is the edge's low end, corner 1 << axis its high end.
void ReferenceMesher::updateVertex(const TsdfBlocks& tsdf, const BlockMeshState& owner, uint32_t cube, int axis) {
    gpu::Vertex& vertex = vertices_[owner.edgeVertex[cube * 3 + uint32_t(axis)]];
    const CubeCorners corners = readCorners(tsdf, cube, minMeshWeight_);
    const int hi = 1 << axis;
    const float dLo = corners.d[0], dHi = corners.d[hi];
    if (!corners.exists[0] || !corners.exists[hi]) return;  // keeps its position

    // The float operations of the shaders' edgeCrossing: the zero crossing, kept off the edge's ends in a refined
    // mesh (docs/REFINEMENT.md, "Vertices"); unrefined, exactly ReferenceVolume::extractBaselineMesh's.
    const float s = edgeCrossing(dLo, dHi, options_.refine);
    const auto local = localCoords(cube);
    float p[3] = {float(owner.coord[0] * int(gpu::BLOCK_SIDE) + local[0]), float(owner.coord[1] * int(gpu::BLOCK_SIDE) + local[1]),
                  float(owner.coord[2] * int(gpu::BLOCK_SIDE) + local[2])};
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
    // Colour: interpolated between the edge's corners like the position (structure/voxel_color.glsl).
    if (params_.colorFusion != ColorFusion::Off) vertex.color = vertexColorOnEdge(corners.color[0], corners.color[hi], s);
}

}  // namespace vkmesh::cpu
