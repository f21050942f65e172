// The mesh state's invariants (ReferenceMesher::checkInvariants), checked by the tests after every frame.
#include "cpu/reference_mesh_internal.h"

#include <string>

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

std::vector<std::string> ReferenceMesher::checkInvariants() const {
    const MarchingCubesTables& tables = marchingCubesTables();
    std::vector<std::string> problems;
    size_t total = 0;
    auto report = [&](const std::string& what) {
        if (++total <= 20) problems.push_back(what);
    };
    auto where = [](const BlockCoord& c, uint32_t cube) {
        const auto l = localCoords(cube);
        return "block (" + std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) +
               ") cube (" + std::to_string(l[0]) + "," + std::to_string(l[1]) + "," + std::to_string(l[2]) + ")";
    };
    auto live = [&](uint32_t v) { return v < vertexCapacity_ && vertices_[v].refcount != gpu::DEAD_REFCOUNT; };

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
                if (v == gpu::EMPTY_SLOT) continue;
                if (!live(v)) report(where(coord, cube) + ": slot " + std::to_string(axis) + " holds a dead vertex " + std::to_string(v));
                else if (vertexOwner_[v] != globalEdgeId(state, cube, axis))
                    report(where(coord, cube) + ": slot " + std::to_string(axis) + " holds vertex " + std::to_string(v) + " owned elsewhere");
            }
            const uint32_t cubeState = state.cubeState[cube];
            const uint32_t type = cubeState & gpu::CUBE_TYPE_MASK;
            const uint32_t chunk = cubeState >> gpu::CUBE_CHUNK_SHIFT;
            const int count = tables.triangleCount[type];
            if (chunk > chunkCapacity_) {
                report(where(coord, cube) + ": chunk index out of range");
                continue;
            }
            if (chunk) {
                ++chunkUsers[chunk - 1];
                if (count == 0) report(where(coord, cube) + ": holds a chunk but its type has no triangles");
                const auto& tris = chunkTriangles_[chunk - 1];
                for (int k = 0; k < int(gpu::TRIANGLES_PER_CHUNK); ++k) {
                    if (tris[3 * k] == gpu::INVALID_INDEX) continue;
                    for (int j = 0; j < 3; ++j) {
                        const uint32_t v = tris[3 * k + j];
                        if (!live(v)) report(where(coord, cube) + ": triangle uses a dead vertex " + std::to_string(v));
                        else ++references[v];
                    }
                }
            }
            if (cubeState & gpu::CUBE_INCOMPLETE) continue;
            if (count > 0 && !chunk) {
                report(where(coord, cube) + ": complete with triangles but no chunk");
                continue;
            }
            if (!chunk) continue;
            // A complete cube's chunk holds exactly its type's triangles on its current edge vertices.
            const auto& tris = chunkTriangles_[chunk - 1];
            const auto local = localCoords(cube);
            for (int k = 0; k < int(gpu::TRIANGLES_PER_CHUNK); ++k) {
                for (int j = 0; j < 3; ++j) {
                    uint32_t expected = gpu::INVALID_INDEX;
                    if (k < count) {
                        const int e = tables.triangleEdges[type][3 * k + j];
                        const auto o = edgeOwnerOffset(e);
                        const Wrapped w = wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
                        expected = mesh[w.neighbour] ? mesh[w.neighbour]->edgeVertex[w.cube * 3 + uint32_t(edgeAxis(e))] : gpu::EMPTY_SLOT;
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
        const gpu::Vertex& vertex = vertices_[v];
        if (vertex.refcount == gpu::DEAD_REFCOUNT) continue;
        ++liveCount;
        if (vertex.refcount == 0) report("vertex " + std::to_string(v) + " is live without triangles");
        if (vertex.refcount != references[v])
            report("vertex " + std::to_string(v) + ": refcount " + std::to_string(vertex.refcount) + " but " +
                   std::to_string(references[v]) + " live triangles use it");
        const uint64_t owner = vertexOwner_[v];
        if (owner / SLOTS_PER_BLOCK >= blockByIndex_.size() ||
            blockByIndex_[owner / SLOTS_PER_BLOCK]->edgeVertex[owner % SLOTS_PER_BLOCK] != v)
            report("vertex " + std::to_string(v) + ": its owner slot does not point back to it");
    }
    std::vector<char> onStack(vertexCapacity_, 0);
    for (uint32_t v : freeVertices_) {
        if (v >= vertexCapacity_ || onStack[v]) report("free vertex stack: entry " + std::to_string(v) + " out of range or repeated");
        else if (vertices_[v].refcount != gpu::DEAD_REFCOUNT) report("free vertex stack: vertex " + std::to_string(v) + " is live");
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
