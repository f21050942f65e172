#include "cpu/reference_baseline.h"

#include "core/marching_cubes.h"
#include "core/refinement.h"

namespace vkmesh::cpu {

using gpu::BLOCK_SIDE;
using gpu::VOXELS_PER_BLOCK;

std::vector<Eigen::Vector3f> baselineMesh(const std::map<BlockCoord, ReferenceBlock>& blocks, float voxelSize,
                                          float minMeshWeight) {
    const MarchingCubesTables& tables = marchingCubesTables();
    const int side = int(BLOCK_SIDE);
    std::vector<Eigen::Vector3f> soup;
    for (const auto& [coord, block] : blocks) {
        // The block itself and its 7 neighbours in +x, +y, +z, indexed like cube corners.
        const ReferenceBlock* neighbour[kCubeCorners];
        for (int i = 0; i < kCubeCorners; ++i) {
            const auto o = cornerOffset(i);
            auto it = blocks.find({coord[0] + o[0], coord[1] + o[1], coord[2] + o[2]});
            neighbour[i] = it == blocks.end() ? nullptr : &it->second;
        }
        for (uint32_t local = 0; local < VOXELS_PER_BLOCK; ++local) {
            const auto cube = localCoords(local);
            float d[kCubeCorners];
            bool observed = true;
            int type = 0;
            for (int c = 0; c < kCubeCorners; ++c) {
                const auto o = cornerOffset(c);
                int g[3] = {cube[0] + o[0], cube[1] + o[1], cube[2] + o[2]};
                int wrap = (g[0] / side) | ((g[1] / side) << 1) | ((g[2] / side) << 2);
                const ReferenceBlock* nb = neighbour[wrap];
                d[c] = 0.0f;
                if (!nb) {
                    observed = false;
                    continue;
                }
                const uint32_t v = localIndex(g[0] % side, g[1] % side, g[2] % side);
                if (nb->weight[v] < minMeshWeight) observed = false;
                d[c] = nb->sdf[v];
                if (d[c] < 0.0f) type |= 1 << c;
            }
            if (!observed) continue;
            for (int t = 0; t < 3 * tables.triangleCount[type]; ++t) {
                int e = tables.triangleEdges[type][t];
                auto [lo, hi] = edgeCorners(e);
                int axis = edgeAxis(e);
                const float s = edgeCrossing(d[lo], d[hi], false);   // the shader's, kept off the edge's ends
                const auto o = cornerOffset(lo);
                float p[3] = {float(coord[0] * side + cube[0] + o[0]), float(coord[1] * side + cube[1] + o[1]),
                              float(coord[2] * side + cube[2] + o[2])};
                p[axis] += s;
                soup.emplace_back(p[0] * voxelSize, p[1] * voxelSize, p[2] * voxelSize);
            }
        }
    }
    return soup;
}

}  // namespace vkmesh::cpu
