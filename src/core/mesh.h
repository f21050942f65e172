// The host mesh: what every part of vkmesh hands around once the mesh has left the GPU (the CPU reference's output,
// the exported mesh, mesh files, analyses, deltas applied). Plain data, no I/O: io/ply.h, io/mesh_file.h read and
// write it.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace vkmesh {

// An indexed triangle mesh, or a point cloud when `triangles` is empty.
struct Mesh {
    std::vector<Eigen::Vector3f> positions;
    std::vector<Eigen::Vector3f> normals;          // empty, or one per vertex
    std::vector<uint32_t> vertexAge;               // empty, or one per vertex: frames since the vertex was created
    std::vector<std::array<uint8_t, 3>> colors;    // empty, or one per vertex: red, green, blue
    std::vector<std::array<uint32_t, 3>> triangles;  // vertex indices, counter-clockwise seen from outside
};

}  // namespace vkmesh
