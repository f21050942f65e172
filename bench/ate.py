#!/usr/bin/env python3
"""ATE and RPE of an estimated camera trajectory against ground truth, as the TUM RGB-D benchmark defines them
(Sturm et al., IROS 2012; its associate.py, evaluate_ate.py and evaluate_rpe.py), with numpy alone.

  /usr/bin/python3 bench/ate.py GROUNDTRUTH ESTIMATED [--max-dt 0.02] [--offset 0] [--delta N | --delta-seconds S]
                                [--json OUT] [--plot PNG]

Files: TUM trajectories, one pose a line, `timestamp tx ty tz qx qy qz qw` (camera to world, metres, quaternion
x y z w), '#' starts a comment, blank lines are skipped, commas are accepted as separators too.

Association (associate.py): every pair (g, e) of a ground-truth stamp and an estimated stamp with
|g - (e + offset)| < max_dt is a candidate; candidates are taken in order of increasing |dt| and a pair is kept
when neither stamp is used yet (greedy, each stamp at most once). max_dt and offset are in the files' time
units: seconds for TUM, frame numbers for ICL-NUIM (whose stamps are frame indices: use e.g. --max-dt 0.5).

ATE (evaluate_ate.py): the estimated positions are aligned to the ground-truth positions by the rigid motion
(rotation + translation, no scale) minimising the squared distances, in closed form (Horn / Umeyama: SVD of
the cross-covariance, with the reflection fixed). The errors are the distances after alignment.

RPE (the paper's definition): for associated pairs i and j = i + delta (in pair order, by time),
E_i = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j) with Q the ground truth and P the estimate; its translation's norm (m) and
its rotation angle (degrees), RMSE over i. No alignment is needed: relative motions do not depend on the
world frame. With --delta-seconds S, j is the pair whose estimated stamp is nearest to stamp_i + S (j > i).

Exit status: 0 success, 2 bad input (the message names the file and line) or fewer than 3 associated pairs.
"""

import argparse
import json
import math
import re
import sys

import numpy as np

MIN_PAIRS = 3


class InputError(Exception):
    pass


def read_trajectory(path):
    """Returns (stamps (N,), positions (N,3), quaternions (N,4) as x y z w, normalised), in file order."""
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            lines = f.readlines()
    except OSError as e:
        raise InputError(f"{path}: cannot read: {e.strerror or e}")
    stamps, poses, seen = [], [], {}
    for number, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [t for t in re.split(r"[,\s]+", line) if t]
        where = f"{path}:{number}"
        if len(fields) != 8:
            raise InputError(f"{where}: expected 8 values 'timestamp tx ty tz qx qy qz qw', found {len(fields)}: "
                             f"{raw.strip()!r}")
        try:
            values = [float(t) for t in fields]
        except ValueError:
            bad = next(t for t in fields if not _is_float(t))
            raise InputError(f"{where}: not a number: {bad!r} in {raw.strip()!r}")
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{where}: not a finite number in {raw.strip()!r}")
        q = np.array(values[4:8])
        norm = float(np.linalg.norm(q))
        if norm < 1e-6:
            raise InputError(f"{where}: the quaternion (qx qy qz qw) is zero: {raw.strip()!r}")
        if abs(norm - 1.0) > 0.1:
            raise InputError(f"{where}: the quaternion (qx qy qz qw) has norm {norm:.4g}, not 1: {raw.strip()!r}")
        if values[0] in seen:
            raise InputError(f"{where}: timestamp {fields[0]} already on line {seen[values[0]]}")
        seen[values[0]] = number
        stamps.append(values[0])
        poses.append(values[1:4] + list(q / norm))
    if not stamps:
        raise InputError(f"{path}: no poses in the file")
    poses = np.array(poses, dtype=np.float64)
    return np.array(stamps, dtype=np.float64), poses[:, 0:3], poses[:, 3:7]


def _is_float(token):
    try:
        float(token)
        return True
    except ValueError:
        return False


def associate(stamps_gt, stamps_est, max_dt, offset):
    """TUM associate.py: greedy, nearest first, each stamp once, |g - (e + offset)| < max_dt.
    Returns index pairs (gt index, est index) sorted by the estimated stamp."""
    order = np.argsort(stamps_gt, kind="stable")
    sorted_gt = stamps_gt[order]
    candidates = []
    for ie, e in enumerate(stamps_est):
        target = e + offset
        lo = np.searchsorted(sorted_gt, target - max_dt, side="left")
        hi = np.searchsorted(sorted_gt, target + max_dt, side="right")
        for k in range(lo, hi):
            dt = abs(sorted_gt[k] - target)
            if dt < max_dt:
                ig = int(order[k])
                candidates.append((dt, stamps_gt[ig], e, ig, ie))
    candidates.sort()  # as associate.py: by |dt|, then the first file's stamp, then the second's
    used_gt, used_est, pairs = set(), set(), []
    for _, _, _, ig, ie in candidates:
        if ig in used_gt or ie in used_est:
            continue
        used_gt.add(ig)
        used_est.add(ie)
        pairs.append((ig, ie))
    pairs.sort(key=lambda p: (stamps_est[p[1]], p[0]))
    return pairs


def align_rigid(model, data):
    """Rotation R and translation t (no scale) minimising sum |R model_i + t - data_i|^2 (Horn / Umeyama)."""
    mu_m = model.mean(axis=0)
    mu_d = data.mean(axis=0)
    cross = (data - mu_d).T @ (model - mu_m)  # sum of d_i m_i^T
    u, _, vt = np.linalg.svd(cross)
    fix = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        fix[2, 2] = -1.0  # the best proper rotation, not a reflection
    rotation = u @ fix @ vt
    translation = mu_d - rotation @ mu_m
    return rotation, translation


def quaternion_to_matrix(q):
    """q = x y z w (unit) -> 3x3 rotation."""
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def to_matrix(position, quaternion):
    m = np.eye(4)
    m[:3, :3] = quaternion_to_matrix(quaternion)
    m[:3, 3] = position
    return m


def inverse_rigid(m):
    inv = np.eye(4)
    inv[:3, :3] = m[:3, :3].T
    inv[:3, 3] = -m[:3, :3].T @ m[:3, 3]
    return inv


def rotation_angle(r):
    """Angle of a rotation matrix in radians, accurate near 0 (atan2 rather than arccos of the trace)."""
    s = 0.5 * math.sqrt((r[2, 1] - r[1, 2]) ** 2 + (r[0, 2] - r[2, 0]) ** 2 + (r[1, 0] - r[0, 1]) ** 2)
    c = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    return math.atan2(s, c)


def statistics(errors):
    return {
        "rmse": float(math.sqrt(np.mean(errors ** 2))),
        "mean": float(np.mean(errors)),
        "median": float(np.median(errors)),
        "std": float(np.std(errors)),
        "min": float(np.min(errors)),
        "max": float(np.max(errors)),
    }


def relative_pose_errors(gt_poses, est_poses, est_stamps, delta_frames, delta_seconds, max_dt):
    """Per-pair RPE (translation m, rotation rad) over the associated poses (in time order)."""
    n = len(gt_poses)
    steps = []
    if delta_seconds is None:
        steps = [(i, i + delta_frames) for i in range(n - delta_frames)]
    else:
        for i in range(n):
            target = est_stamps[i] + delta_seconds
            if target > est_stamps[-1] + max_dt:
                break
            j = int(np.argmin(np.abs(est_stamps - target)))
            if j > i:
                steps.append((i, j))
    trans, rot = [], []
    for i, j in steps:
        rel_gt = inverse_rigid(gt_poses[i]) @ gt_poses[j]
        rel_est = inverse_rigid(est_poses[i]) @ est_poses[j]
        error = inverse_rigid(rel_gt) @ rel_est
        trans.append(float(np.linalg.norm(error[:3, 3])))
        rot.append(rotation_angle(error[:3, :3]))
    return np.array(trans), np.array(rot)


def evaluate(gt_path, est_path, max_dt=0.02, offset=0.0, delta=1, delta_seconds=None):
    """Everything the JSON holds, as a dict. Raises InputError on bad input or too few pairs."""
    stamps_gt, pos_gt, quat_gt = read_trajectory(gt_path)
    stamps_est, pos_est, quat_est = read_trajectory(est_path)
    pairs = associate(stamps_gt, stamps_est, max_dt, offset)
    if len(pairs) < MIN_PAIRS:
        raise InputError(
            f"only {len(pairs)} pose pairs associate between {gt_path} ({len(stamps_gt)} poses, stamps "
            f"{stamps_gt.min():.6f}..{stamps_gt.max():.6f}) and {est_path} ({len(stamps_est)} poses, stamps "
            f"{stamps_est.min():.6f}..{stamps_est.max():.6f}) within --max-dt {max_dt} (offset {offset}); "
            f"at least {MIN_PAIRS} are needed. Check that both files use the same time base (frame-index "
            f"stamps, as ICL-NUIM's, need e.g. --max-dt 0.5) or set --offset")
    ig = np.array([p[0] for p in pairs])
    ie = np.array([p[1] for p in pairs])

    rotation, translation = align_rigid(pos_est[ie], pos_gt[ig])
    aligned = pos_est[ie] @ rotation.T + translation
    ate_errors = np.linalg.norm(aligned - pos_gt[ig], axis=1)

    gt_poses = [to_matrix(pos_gt[k], quat_gt[k]) for k in ig]
    est_poses = [to_matrix(pos_est[k], quat_est[k]) for k in ie]
    rpe_t, rpe_r = relative_pose_errors(gt_poses, est_poses, stamps_est[ie], delta, delta_seconds, max_dt)
    rpe = {"delta": delta if delta_seconds is None else None,
           "delta_seconds": delta_seconds,
           "pairs": int(len(rpe_t)),
           "trans_rmse": float(math.sqrt(np.mean(rpe_t ** 2))) if len(rpe_t) else None,
           "rot_rmse_deg": float(math.degrees(math.sqrt(np.mean(rpe_r ** 2)))) if len(rpe_r) else None}
    return {
        "groundtruth": str(gt_path),
        "estimated": str(est_path),
        "max_dt": max_dt,
        "offset": offset,
        "pairs": len(pairs),
        "unmatched": {"groundtruth": int(len(stamps_gt) - len(pairs)),
                      "estimated": int(len(stamps_est) - len(pairs))},
        "ate": statistics(ate_errors),
        "rpe": rpe,
        "alignment": {"note": "p_groundtruth ~= rotation @ p_estimated + translation (no scale)",
                      "rotation": rotation.tolist(),
                      "translation": translation.tolist()},
        "_plot": (pos_gt[ig], aligned),
    }


def summary(result):
    a, r, u = result["ate"], result["rpe"], result["unmatched"]
    lines = [
        f"pairs        {result['pairs']} associated within {result['max_dt']} (offset {result['offset']}); "
        f"unmatched: {u['groundtruth']} ground truth, {u['estimated']} estimated",
        f"ATE (m)      rmse {a['rmse']:.6f}  mean {a['mean']:.6f}  median {a['median']:.6f}  std {a['std']:.6f}  "
        f"min {a['min']:.6f}  max {a['max']:.6f}",
    ]
    step = f"{r['delta']} frame(s)" if r["delta_seconds"] is None else f"{r['delta_seconds']} s"
    if r["pairs"]:
        lines.append(f"RPE ({step})  trans rmse {r['trans_rmse']:.6f} m  rot rmse {r['rot_rmse_deg']:.6f} deg  "
                     f"over {r['pairs']} steps")
    else:
        lines.append(f"RPE ({step})  no steps (the trajectory is shorter than the delta)")
    return "\n".join(lines)


def plot(result, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("ate.py: --plot skipped: matplotlib is not available", file=sys.stderr)
        return
    gt, est = result["_plot"]
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.plot(gt[:, 0], gt[:, 1], "k-", label="ground truth")
    ax.plot(est[:, 0], est[:, 1], "b-", label="estimated (aligned)")
    for g, e in zip(gt, est):
        ax.plot([g[0], e[0]], [g[1], e[1]], "r-", linewidth=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"ATE rmse {result['ate']['rmse'] * 100:.2f} cm, {result['pairs']} pairs")
    ax.legend()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="ate.py",
        description="ATE (rigid Horn alignment, no scale) and RPE of an estimated TUM trajectory against ground "
                    "truth, as the TUM RGB-D benchmark defines them. Files: 'timestamp tx ty tz qx qy qz qw' a "
                    "line, '#' comments, spaces or commas.",
        epilog="Exit status: 0 ok; 2 bad input (file and line named) or fewer than 3 associated pairs.")
    parser.add_argument("groundtruth", help="ground-truth trajectory (TUM format)")
    parser.add_argument("estimated", help="estimated trajectory (TUM format)")
    parser.add_argument("--max-dt", type=float, default=0.02,
                        help="largest |t_gt - (t_est + offset)| of an associated pair, in the files' time units "
                             "(default 0.02: 20 ms for TUM's seconds). For frame-index timestamps (ICL-NUIM: "
                             "0, 1, 2, ...) it must be < 1: use e.g. 0.5")
    parser.add_argument("--offset", type=float, default=0.0,
                        help="added to the estimated stamps before association (default 0)")
    step = parser.add_mutually_exclusive_group()
    step.add_argument("--delta", type=int, default=1,
                      help="RPE step in associated frames (default 1)")
    step.add_argument("--delta-seconds", type=float, default=None,
                      help="RPE step in the files' time units instead of frames")
    parser.add_argument("--json", metavar="OUT", help="write the results as JSON")
    parser.add_argument("--plot", metavar="PNG",
                        help="x-y plot of both trajectories (only when matplotlib is installed; skipped otherwise)")
    args = parser.parse_args(argv)
    if not args.max_dt > 0:
        parser.error("--max-dt must be > 0")
    if args.delta < 1:
        parser.error("--delta must be >= 1")
    if args.delta_seconds is not None and not args.delta_seconds > 0:
        parser.error("--delta-seconds must be > 0")
    try:
        result = evaluate(args.groundtruth, args.estimated, args.max_dt, args.offset, args.delta,
                          args.delta_seconds)
    except InputError as e:
        print(f"ate.py: error: {e}", file=sys.stderr)
        return 2
    print(summary(result))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({k: v for k, v in result.items() if not k.startswith("_")}, f, indent=2)
            f.write("\n")
    if args.plot:
        plot(result, args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
