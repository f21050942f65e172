#!/usr/bin/python3
"""What one perfect loop could do for a drifted trajectory (docs/LOOP_CLOSURE.md, "Limits").

Builds a pose graph from a trajectory tracked without loop closure (every frame a node, odometry edges with the loop
closer's uncertainty model: 5 mm + 2 % of the distance, 0.3 degrees + 2 % of the angle), adds one loop edge between
frame 0 and frame LOOP taken from the ground truth (1 mm, 0.05 degrees), solves it with Open3D's
global_optimization (Debian's python3-open3d), and writes frames 0..LOOP as a TUM trajectory for bench/ate.py.

    bench/loop_oracle.py GROUNDTRUTH TRACKED LOOP OUT
    bench/ate.py GROUNDTRUTH OUT          # against the same frames of a run with loop closure (head -n LOOP+1)
"""
import sys

import numpy as np
import open3d as o3d


def to_matrix(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def to_quaternion(m):
    w = np.sqrt(max(0.0, 1 + np.trace(m))) / 2
    if w > 1e-6:
        return np.array([(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w), (m[1, 0] - m[0, 1]) / (4 * w), w])
    i = int(np.argmax(np.diag(m)))
    j, k = (i + 1) % 3, (i + 2) % 3
    r = np.sqrt(1 + m[i, i] - m[j, j] - m[k, k])
    q = np.zeros(4)
    q[i], q[j], q[k], q[3] = r / 2, (m[j, i] + m[i, j]) / (2 * r), (m[k, i] + m[i, k]) / (2 * r), (m[k, j] - m[j, k]) / (2 * r)
    return q


def load(path):
    rows = np.loadtxt(path, comments="#")
    poses = []
    for r in rows:
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = to_matrix(r[4:8]), r[1:4]
        poses.append(pose)
    return rows[:, 0], poses


def information(sigma_metres, sigma_radians):
    info = np.zeros((6, 6))   # Open3D's twist order: rotation, then translation
    info[:3, :3] = np.eye(3) / sigma_radians ** 2
    info[3:, 3:] = np.eye(3) / sigma_metres ** 2
    return info


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    _, truth = load(sys.argv[1])
    stamps, tracked = load(sys.argv[2])
    loop = int(sys.argv[3])
    if not 0 < loop < min(len(truth), len(tracked)):
        sys.exit(f"loop frame {loop} is not within both trajectories ({len(truth)} and {len(tracked)} poses)")
    graph = o3d.pipelines.registration.PoseGraph()
    for pose in tracked[:loop + 1]:
        graph.nodes.append(o3d.pipelines.registration.PoseGraphNode(pose))
    for i in range(1, loop + 1):
        motion = np.linalg.inv(tracked[i - 1]) @ tracked[i]   # frame i's points into frame i-1's
        metres = np.linalg.norm(motion[:3, 3])
        radians = np.arccos(np.clip((np.trace(motion[:3, :3]) - 1) / 2, -1, 1))
        graph.edges.append(o3d.pipelines.registration.PoseGraphEdge(
            i, i - 1, motion, information(0.005 + 0.02 * metres, np.radians(0.3) + 0.02 * radians), uncertain=False))
    exact = np.linalg.inv(truth[0]) @ truth[loop]
    graph.edges.append(o3d.pipelines.registration.PoseGraphEdge(loop, 0, exact, information(0.001, np.radians(0.05)), uncertain=False))
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    o3d.pipelines.registration.global_optimization(
        graph, o3d.pipelines.registration.GlobalOptimizationLevenbergMarquardt(),
        o3d.pipelines.registration.GlobalOptimizationConvergenceCriteria(),
        o3d.pipelines.registration.GlobalOptimizationOption(max_correspondence_distance=0.05, edge_prune_threshold=1e9, reference_node=0))
    with open(sys.argv[4], "w") as out:
        for stamp, node in zip(stamps, graph.nodes):
            p, q = node.pose, to_quaternion(node.pose[:3, :3])
            out.write(f"{stamp:.6f} {p[0, 3]:.9f} {p[1, 3]:.9f} {p[2, 3]:.9f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")


if __name__ == "__main__":
    main()
