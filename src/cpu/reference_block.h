// What every stage of the CPU reference shares: block coordinates, a block's TSDF corners and the index
// arithmetic inside a block, with the grid constants of shaders_comp/shared_layout.h (the GPU's).
#pragma once

#include <array>
#include <bitset>
#include <cstdint>

#include "shared_layout.h"

namespace vkmesh::cpu {

using BlockCoord = std::array<int, 3>;

// The TSDF corners of one block, index x + BLOCK_SIDE (y + BLOCK_SIDE z) (the GPU's voxel order), with their
// colour words (structure/voxel_color.glsl; 0 = no colour). A corner is its step sum and weight (the GPU's
// two arrays, core/tsdf_corner.h); `sdf` is its distance in metres, tsdfMean(sum, weight), kept beside them
// for the stages that read distances (fusion and recycling update all three; a test of the mesher alone may
// set sdf and weight directly).
struct ReferenceBlock {
    std::array<int32_t, gpu::VOXELS_PER_BLOCK> sdfSum{};
    std::array<float, gpu::VOXELS_PER_BLOCK> sdf{};
    std::array<float, gpu::VOXELS_PER_BLOCK> weight{};
    std::array<uint32_t, gpu::VOXELS_PER_BLOCK> color{};
};

// One bit per cube (or corner) of a block, same index.
using CubeMask = std::bitset<gpu::VOXELS_PER_BLOCK>;

// Local (x, y, z) of a corner or cube index, and back.
inline std::array<int, 3> localCoords(uint32_t index) {
    const uint32_t side = gpu::BLOCK_SIDE;
    return {int(index % side), int((index / side) % side), int(index / (side * side))};
}
inline uint32_t localIndex(int x, int y, int z) {
    const int side = int(gpu::BLOCK_SIDE);
    return uint32_t(x + side * (y + side * z));
}

// The block holding global voxel (or cube) coordinate a along one axis: floor(a / BLOCK_SIDE).
inline int blockOf(int a) {
    const int side = int(gpu::BLOCK_SIDE);
    return a >= 0 ? a / side : -((-a + side - 1) / side);
}

// x' = R x + t with the rows of [R | t] (gpu::FramePush's layout), the operations in the order of
// structure/frame.glsl's transformPoint so that both round alike.
template <typename Vec3>
Vec3 transformRows(const float rows[3][4], const Vec3& p) {
    Vec3 q;
    for (int i = 0; i < 3; ++i) q[i] = rows[i][0] * p[0] + rows[i][1] * p[1] + rows[i][2] * p[2] + rows[i][3];
    return q;
}

}  // namespace vkmesh::cpu
