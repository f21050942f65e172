// The CPU reference of the baseline mesh (shaders_comp/baseline_mesh/mesh_baseline.comp): every observed cube's marching-
// cubes triangles with 3 vertices of their own (a triangle soup). Its vertex positions are the float
// operations the incremental mesh's vertices use too, so the two agree bit for bit.
#pragma once

#include <Eigen/Core>

#include <map>
#include <vector>

#include "cpu/reference_block.h"

namespace vkmesh::cpu {

// Blocks in coordinate order, cubes in index order; a cube is meshed when its 8 corners exist and all have
// weight >= minMeshWeight.
std::vector<Eigen::Vector3f> baselineMesh(const std::map<BlockCoord, ReferenceBlock>& blocks, float voxelSize,
                                          float minMeshWeight);

}  // namespace vkmesh::cpu
