#!/usr/bin/env python3
"""vkmesh and Open3D: fuses a dataset with vkmesh, hands the mesh to Open3D as a TriangleMesh (here to clean it
up and write it), and brings an Open3D mesh back as a vkmesh.Mesh. Needs python3-open3d (Debian 12: 0.16).

    PYTHONPATH=build/python python3 examples/python/open3d_interop.py DATASET -o mesh_open3d.ply
"""

import argparse

import numpy as np
import open3d as o3d

import vkmesh


def to_open3d(mesh: vkmesh.Mesh) -> o3d.geometry.TriangleMesh:
    """A vkmesh.Mesh as an Open3D TriangleMesh (positions, triangles, normals and colours; Open3D keeps colours as
    floats in [0, 1] and indices as int32)."""
    out = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices.astype(np.float64)),
                                    o3d.utility.Vector3iVector(mesh.triangles.astype(np.int32)))
    if mesh.normals is not None:
        out.vertex_normals = o3d.utility.Vector3dVector(mesh.normals.astype(np.float64))
    if mesh.colors is not None:
        out.vertex_colors = o3d.utility.Vector3dVector(mesh.colors / 255.0)
    return out


def from_open3d(mesh: o3d.geometry.TriangleMesh) -> vkmesh.Mesh:
    """An Open3D TriangleMesh as a vkmesh.Mesh (ages are vkmesh's own: none)."""
    normals = np.asarray(mesh.vertex_normals) if mesh.has_vertex_normals() else None
    colors = None
    if mesh.has_vertex_colors():
        colors = (np.clip(np.asarray(mesh.vertex_colors), 0, 1) * 255).round().astype(np.uint8)
    return vkmesh.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.triangles), normals=normals, colors=colors)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", help="dataset folder")
    parser.add_argument("-o", "--output", required=True, help="PLY file that Open3D writes")
    parser.add_argument("--voxel", type=float, default=0.03, help="voxel size in metres (default 0.03)")
    parser.add_argument("--frames", type=int, default=0, help="use at most N frames (0 = all)")
    args = parser.parse_args()

    r = vkmesh.Reconstructor(voxel_size=args.voxel)
    for frame in vkmesh.open_dataset(args.dataset, frames=args.frames):
        r.integrate(frame.depth, frame.intrinsics, frame.pose, color=frame.color)
    mesh = to_open3d(r.mesh())
    # Anything Open3D offers from here; e.g. drop the small disconnected pieces a noisy sequence leaves.
    clusters, sizes, _ = mesh.cluster_connected_triangles()
    clusters, sizes = np.asarray(clusters), np.asarray(sizes)
    mesh.remove_triangles_by_mask(sizes[clusters] < 100)
    mesh.remove_unreferenced_vertices()
    o3d.io.write_triangle_mesh(args.output, mesh, write_ascii=False)
    back = from_open3d(o3d.io.read_triangle_mesh(args.output))
    print(f"Open3D wrote {args.output}: {len(back.vertices)} vertices, {len(back.triangles)} triangles "
          f"(vkmesh fused {len(r.mesh().triangles)}; pieces under 100 triangles removed)")


if __name__ == "__main__":
    main()
