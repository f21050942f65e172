// Triangulation (docs/MESH.md, pass 3; shaders_comp/triangulate/mesh_triangulate.comp): a cube whose type changed (or
// that is INCOMPLETE) releases its triangles and builds its new type's on its edge vertices, in its chunk.
#include "cpu/reference_mesh_internal.h"

#include <algorithm>

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

void ReferenceMesher::releaseReference(uint32_t v) {
    gpu::Vertex& vertex = vertices_.at(v);
    if (vertex.refcount == 0 || vertex.refcount == gpu::DEAD_REFCOUNT)
        throw std::logic_error("ReferenceMesher: releasing a triangle of a vertex without references");
    if (--vertex.refcount == 0) gcCandidates_.push_back(v);
}

void ReferenceMesher::triangulate(DirtyBlock& b, MeshFrameStats& stats) {
    const MarchingCubesTables& tables = marchingCubesTables();
    for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
        if (!b.retype.test(cube)) continue;
        const uint32_t state = b.state->cubeState[cube];
        const uint32_t oldType = state & gpu::CUBE_TYPE_MASK;
        const uint32_t newType = b.newType[cube];
        if (newType == oldType && !(state & gpu::CUBE_INCOMPLETE)) continue;  // temporal consistency: keep the triangles
        ++stats.cubesRetyped;

        uint32_t chunk = state >> gpu::CUBE_CHUNK_SHIFT;  // chunk index + 1, 0 = none
        if (chunk) {                           // release every existing triangle
            auto& tris = chunkTriangles_[chunk - 1];
            for (int k = 0; k < int(gpu::TRIANGLES_PER_CHUNK); ++k) {
                if (tris[3 * k] == gpu::INVALID_INDEX) continue;
                for (int j = 0; j < 3; ++j) releaseReference(tris[3 * k + j]);
                tris[3 * k] = tris[3 * k + 1] = tris[3 * k + 2] = gpu::INVALID_INDEX;
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
                    newState |= gpu::CUBE_INCOMPLETE;
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
                        if (v[j] == gpu::EMPTY_SLOT) valid = false;
                    }
                    if (!valid) {
                        ++stats.trianglesInvalid;
                        newState |= gpu::CUBE_INCOMPLETE;
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
        b.state->cubeState[cube] = newState | (chunk << gpu::CUBE_CHUNK_SHIFT);
    }
}

}  // namespace vkmesh::cpu
