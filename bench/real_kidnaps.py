#!/usr/bin/env python3
"""Real kidnap test cases: a TUM-layout dataset (TUM RGB-D, ICL-NUIM) with runs of frames cut out, and the score
of a `vkmesh fuse --track --loop-closure` run on it (../shared/docs/real-data.md; docs/LOOP_CLOSURE.md).

  /usr/bin/python3 bench/real_kidnaps.py make DATASET OUT (--cut START:COUNT ... | --auto N)
  /usr/bin/python3 bench/real_kidnaps.py mirror DATASET OUT --frames N [--alternate]
  /usr/bin/python3 bench/real_kidnaps.py score OUT RUN_DIR [--json FILE]

make: OUT gets depth.txt and rgb.txt without the cut frames (associations.txt too, if the dataset has one), copies
of the other files and symlinks to the image folders, so that `vkmesh fuse OUT` reads the original minus those
frames. Frames are numbered as vkmesh numbers them: the data lines of depth.txt in time order, from 0 (the file must
be sorted; with --track a frame without a ground-truth pose counts too, while `vkmesh frames` and fuse without --track
skip it); START is the first frame cut ("lines 59-98 removed" in real-data.md is --cut 59:40). vkmesh picks the
intrinsics by the folder's name (fr1/freiburg1, icl), so OUT's name must select the original's camera preset.
--auto N picks N cuts of 20-40 frames with at least 40 frames before, between and after them, whose ground-truth jump
(last kept frame before -> first kept frame after) is at most 80 cm and 120 degrees and at least 30 cm or 30 degrees.
A landing is "mapped" when a kept frame before it is within 30 cm and 30 degrees of its true pose (a proxy for "that
view was seen": same place, overlapping view cone), else "unmapped". OUT/kidnaps.json lists the cuts.

mirror: OUT is a there-and-back sequence: frames 0..N-1 of DATASET, then N-2..0 again (2N-1 frames), so that the
way back revisits what the way there mapped. The way back gets new timestamps (2 t_last - t: increasing, and ICL-
NUIM's stay frame indices); OUT's depth.txt, rgb.txt (each frame's nearest colour image) and groundtruth.txt (each
frame's pose) are written with them, the image folders are symlinks. `make OUT ...` then cuts it: jumps on the way
back land on mapped places. --alternate: the way there takes the even frames of 0..N-1 and the way back the odd ones
between them, so that the way back sees the places again in images the way there did not have (a real revisit, not
the same images: tests/gpu/test_loop_closure.cpp, RealLoopClosure.IclRevisitAfterFiveMetresIsProposedAndVerified).

score: reads what this run wrote (it runs nothing):
  build/vkmesh fuse OUT --track --loop-closure --trajectory-online RUN_DIR/online.txt \
      --trajectory RUN_DIR/final.txt --stats RUN_DIR/stats.json -o /dev/null -q [--frames N]
The run starts at the first frame's ground-truth pose, so poses share the dataset's world frame: errors are taken
without alignment. Per kidnap (its window runs from the landing frame L to the next landing or the run's end):
  detected   a frame in L..L+2 was lost (stats tracking.lost) or went to relocalisation (loop_closure.relocalisation)
  recovered  mapped landing: a frame in L..L+5 fused within 5 cm and 5 degrees (relocalised or tracked)
  unmapped   until the camera is back over a place seen before L (the rule above): no fused frame > 5 cm off
  false      relocalised frames > 5 cm or 5 degrees off
  max / >5cm the largest position error of a fused (tracked or relocalised, not lost) frame, online poses, and how
             many fused frames are > 5 cm off
  ATE        RMSE of the fused frames' position errors, online poses, unaligned (shared world frame)
  pass       detected; recovered with no frame fused > 5 cm off before (mapped) or the unmapped rule; no false one
  vs map     each relocalised frame's error against the map it landed on: its pose seen from the fused frame before L
             whose true pose is nearest, against the same relative pose in the ground truth (the map's drift there
             cancels; for an unmapped landing that frame is far off, and drift between the two places does not)
"""

import argparse
import json
import math
import os
import re
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ate import InputError, quaternion_to_matrix, read_trajectory, rotation_angle  # noqa: E402

CUT_MIN, CUT_MAX, GAP = 20, 40, 40               # --auto: cut lengths, frames kept before, between and after cuts
JUMP_M, JUMP_DEG = (0.30, 0.80), (30.0, 120.0)    # --auto: jump bounds
SEEN_M, SEEN_DEG = 0.30, 30.0                     # "seen before"
OK_M, OK_DEG = 0.05, 5.0                          # a correct pose
DETECT_WITHIN, RECOVER_WITHIN = 2, 5              # frames after the landing


def fail(message):
    sys.exit(f"real_kidnaps.py: {message}")


def read_list(path):
    """[(timestamp, line number)] of a 'timestamp path' list such as depth.txt, comments and blank lines dropped."""
    with open(path, encoding="utf-8") as f:
        lines = enumerate((raw.split() for raw in f), start=1)
        return [(float(t[0]), n) for n, t in lines if t and not t[0].startswith("#")]


class Sequence:
    """A TUM-layout folder's depth frames (vkmesh's numbering) with their ground-truth poses (None without one)."""

    def __init__(self, folder):
        self.folder = folder
        self.frames = read_list(os.path.join(folder, "depth.txt"))
        self.stamps = np.array([t for t, _ in self.frames])
        if np.any(np.diff(self.stamps) <= 0):
            fail(f"{folder}/depth.txt is not sorted by time: vkmesh numbers frames in time order; sort it first")
        t = self.stamps
        self.frame_indices = bool(np.all((t >= 0) & (t < 1e6) & (t == np.floor(t))))   # ICL-NUIM's stamps
        tolerance = 0.5 if self.frame_indices else 0.020   # vkmesh's: ICL-NUIM same index, TUM 20 ms
        gt_t, gt_p, gt_q = read_trajectory(os.path.join(folder, "groundtruth.txt"))
        order = np.argsort(gt_t)
        gt_t, gt_p, gt_q = gt_t[order], gt_p[order], gt_q[order]
        self.poses = []
        for t in self.stamps:
            k = int(np.argmin(np.abs(gt_t - t)))
            near = abs(gt_t[k] - t) < tolerance if self.frame_indices else abs(gt_t[k] - t) <= tolerance
            self.poses.append((gt_p[k], quaternion_to_matrix(gt_q[k])) if near else None)

    def preset(self, folder):
        """The camera preset vkmesh's TUM reader picks for this sequence in a folder of that (real) name."""
        name = os.path.basename(os.path.realpath(folder)).lower()
        word = lambda w: re.search(r"(?<![a-z])" + w + r"(?!\d)", name) is not None  # noqa: E731
        sensor = next((n for n in (1, 2, 3) if word(f"freiburg{n}") or word(f"fr{n}")), 0)
        if word("icl") or (sensor == 0 and self.frame_indices):
            return "icl_nuim"
        return f"tum_fr{sensor}" if sensor else "tum_default"


def difference(a, b):
    """(metres, degrees) between two poses (position, rotation matrix)."""
    return float(np.linalg.norm(a[0] - b[0])), math.degrees(rotation_angle(a[1].T @ b[1]))


def nearest_seen(poses, target, before):
    """The frame among poses[:before] closest to target by max(d / 30 cm, angle / 30 deg): (frame, m, deg) or None."""
    best = None
    for k in range(before):
        if poses[k] is not None:
            m, deg = difference(poses[k], target)
            if best is None or max(m / SEEN_M, deg / SEEN_DEG) < max(best[1] / SEEN_M, best[2] / SEEN_DEG):
                best = (k, m, deg)
    return best


def is_seen(best):
    return best is not None and best[1] <= SEEN_M and best[2] <= SEEN_DEG


def jump_ok(m, deg):
    return m <= JUMP_M[1] and deg <= JUMP_DEG[1] and (m >= JUMP_M[0] or deg >= JUMP_DEG[0])


def auto_cuts(seq, n):
    """N cuts (start, count), spread over the sequence when they fit so, else packed from the start."""
    total, poses = len(seq.frames), seq.poses

    def first_cut(lowest):   # the earliest start with a valid cut; of its cuts, the one with the largest jump
        for s in range(max(lowest, GAP), total - CUT_MIN - GAP + 1):
            counts = range(CUT_MIN, min(CUT_MAX, total - GAP - s) + 1)
            jumps = [(max(m / JUMP_M[0], deg / JUMP_DEG[0]), c) for c in counts
                     if poses[s - 1] is not None and poses[s + c] is not None
                     for m, deg in [difference(poses[s - 1], poses[s + c])] if jump_ok(m, deg)]
            if jumps:
                return s, max(jumps)[1]
        return None

    for spread in (True, False):
        cuts, end = [], 0
        for k in range(n):
            cut = first_cut(max(end + GAP, k * total // n if spread else 0))
            if cut is None:
                break
            cuts.append(cut)
            end = cut[0] + cut[1]
        if len(cuts) == n:
            return cuts
    fail(f"--auto {n}: only {len(cuts)} cuts fit {seq.folder} ({total} frames) under the rules; ask for fewer")


def nearest_index(sorted_stamps, t):
    """vkmesh's nearestInTime: the first entry >= t unless the one before is strictly nearer."""
    i = int(np.searchsorted(sorted_stamps, t, side="left"))
    if i == len(sorted_stamps) or (i > 0 and t - sorted_stamps[i - 1] < sorted_stamps[i] - t):
        i -= 1
    return i


def write_filtered(source, target, keep, note):
    """Copies source to target with the data lines for which keep(index, tokens) is false left out."""
    with open(source, encoding="utf-8") as f, open(target, "w", encoding="utf-8") as out:
        out.write(note)
        index = 0
        for raw in f:
            tokens = raw.split()
            if not tokens or tokens[0].startswith("#"):
                out.write(raw)
                continue
            if keep(index, tokens):
                out.write(raw)
            index += 1


def cmd_make(args):
    seq = Sequence(args.dataset)
    total = len(seq.frames)
    if os.path.realpath(args.out) == os.path.realpath(args.dataset):
        fail("OUT is the dataset itself")
    preset = seq.preset(args.dataset)
    if seq.preset(args.out) != preset and not os.path.exists(os.path.join(args.dataset, "camera.json")):
        fail(f"vkmesh picks intrinsics by folder name: {os.path.basename(os.path.abspath(args.out))!r} would get "
             f"preset {seq.preset(args.out)}, the dataset's is {preset}; keep its sensor word (fr1, icl) in OUT's name")
    if args.auto:
        cuts = auto_cuts(seq, args.auto)
    else:
        cuts = sorted(tuple(int(v) for v in c.split(":")) for c in args.cut)
        for (s, c), nxt in zip(cuts, cuts[1:] + [(total + 1, 0)]):
            if s < 1 or c < 1 or s + c >= min(total, nxt[0]):
                fail(f"--cut {s}:{c}: a cut must keep frame 0, and a frame after it and before the next cut "
                     f"({total} frames)")
    cut = set(f for s, c in cuts for f in range(s, s + c))
    kept = [f for f in range(total) if f not in cut]
    renumber = {f: i for i, f in enumerate(kept)}
    kept_poses = [seq.poses[f] for f in kept]
    kidnaps = []
    for s, c in cuts:
        landing = renumber[s + c]
        entry = {"cut_start": s, "cut_count": c, "cut_depth_txt_line": seq.frames[s][1], "landing_frame": landing,
                 "landing_original_frame": s + c, "timestamp": seq.frames[s + c][0], "jump_m": None, "jump_deg": None,
                 "landing": "unknown (no ground truth)", "nearest_seen": None}
        if seq.poses[s - 1] is not None and seq.poses[s + c] is not None:
            m, deg = difference(seq.poses[s - 1], seq.poses[s + c])
            best = nearest_seen(kept_poses, seq.poses[s + c], landing)
            entry.update(jump_m=round(m, 4), jump_deg=round(deg, 2), landing="mapped" if is_seen(best) else "unmapped",
                         nearest_seen=best and {"frame": best[0], "m": round(best[1], 4), "deg": round(best[2], 2)})
        kidnaps.append(entry)

    os.makedirs(args.out, exist_ok=True)
    note = (f"# real_kidnaps.py: frames {', '.join(f'{s}-{s + c - 1}' for s, c in cuts)} (0-based, of {total}) of "
            f"{os.path.abspath(args.dataset)} removed\n")
    write_filtered(os.path.join(args.dataset, "depth.txt"), os.path.join(args.out, "depth.txt"),
                   lambda i, _: i not in cut, note)
    cut_stamps = {seq.frames[f][0] for f in cut}
    for name in sorted(os.listdir(args.dataset)):
        source, target = os.path.join(args.dataset, name), os.path.join(args.out, name)
        if name in ("depth.txt", "kidnaps.json"):
            continue
        if os.path.isdir(target) and not os.path.islink(target):
            fail(f"{target} is a folder; OUT should be new or made by this script")
        if os.path.lexists(target):
            os.remove(target)
        if name == "rgb.txt":
            # Drop the colour images that are the nearest (vkmesh's pairing) of a cut frame and of no kept frame:
            # every kept frame keeps its own nearest image, so its colour is unchanged.
            rgb = sorted(t for t, _ in read_list(source))
            nearest = lambda frames: {rgb[nearest_index(rgb, seq.frames[f][0])] for f in frames}  # noqa: E731
            drop = nearest(cut) - nearest(kept) if rgb else set()
            write_filtered(source, target, lambda _, tokens: float(tokens[0]) not in drop, note)
        elif name == "associations.txt":   # read only without depth.txt; kept consistent anyway
            def keep(_, tokens):
                return not any("depth" in tokens[i + 1].lower() and float(tokens[i]) in cut_stamps
                               for i in range(len(tokens) - 1))
            write_filtered(source, target, keep, note)
        elif os.path.isdir(source):
            os.symlink(os.path.abspath(source), target)
        else:
            shutil.copyfile(source, target)
    result = {"dataset": os.path.abspath(args.dataset), "frames_original": total, "frames": len(kept),
              "cuts": [list(c) for c in cuts],
              "rules": {"auto": {"cut_frames": [CUT_MIN, CUT_MAX], "frames_before_between_after": GAP,
                                 "jump": "m <= 0.80 and deg <= 120 and (m >= 0.30 or deg >= 30)"},
                        "mapped": "a kept frame before the landing within 0.30 m and 30 degrees of its true pose",
                        "frames": "0-based, as vkmesh numbers OUT's frames (cut_start: the original's numbering)"},
              "kidnaps": kidnaps}
    with open(os.path.join(args.out, "kidnaps.json"), "w", encoding="utf-8") as f:
        json.dump(result, f, indent=1)
    print(json.dumps(result, indent=1))


def cmd_mirror(args):
    seq = Sequence(args.dataset)
    n = args.frames
    if not 2 <= n <= len(seq.frames):
        fail(f"--frames {n}: the dataset has {len(seq.frames)} frames")
    if seq.preset(args.out) != seq.preset(args.dataset):
        fail("vkmesh picks intrinsics by folder name: keep the dataset's sensor word (fr1, icl) in OUT's name")
    missing = [f for f in range(n) if seq.poses[f] is None]
    if missing:
        fail(f"frames {missing[:5]} of {args.dataset} have no ground-truth pose")
    with open(os.path.join(args.dataset, "depth.txt"), encoding="utf-8") as f:
        data = [raw.split() for raw in f if raw.split() and not raw.startswith("#")]
    depth_paths = [tokens[1] for tokens in data]
    rgb = read_list(os.path.join(args.dataset, "rgb.txt"))
    with open(os.path.join(args.dataset, "rgb.txt"), encoding="utf-8") as f:
        rgb_paths = [raw.split()[1] for raw in f if raw.split() and not raw.startswith("#")]
    rgb_stamps = np.array([t for t, _ in rgb])
    if args.alternate:
        if n < 3:
            fail(f"--frames {n} --alternate: at least 3 frames (0 and 2 there, 1 back)")
        there = list(range(0, n, 2))
        back = [f for f in range(there[-1] - 1, 0, -1) if f % 2 == 1]
    else:
        there, back = list(range(n)), list(range(n - 2, -1, -1))
    last = seq.stamps[there[-1]]
    order = there + back
    stamps = [seq.stamps[f] if k < len(there) else 2 * last - seq.stamps[f] for k, f in enumerate(order)]
    os.makedirs(args.out, exist_ok=True)
    fmt = (lambda t: f"{t:.0f}") if seq.frame_indices else (lambda t: f"{t:.6f}")
    what = f"frames {there[0]}-{there[-1]} then {back[0]}-{back[-1]}" + (", every other one" if args.alternate else "")
    note = f"# real_kidnaps.py mirror: {what} of {os.path.abspath(args.dataset)}\n"
    with open(os.path.join(args.out, "depth.txt"), "w", encoding="utf-8") as d, \
            open(os.path.join(args.out, "rgb.txt"), "w", encoding="utf-8") as c, \
            open(os.path.join(args.out, "groundtruth.txt"), "w", encoding="utf-8") as g:
        for out in (d, c, g):
            out.write(note)
        g.write("# timestamp tx ty tz qx qy qz qw\n")
        for f, t in zip(order, stamps):
            d.write(f"{fmt(t)} {depth_paths[f]}\n")
            if len(rgb_stamps):
                c.write(f"{fmt(t)} {rgb_paths[nearest_index(rgb_stamps, seq.stamps[f])]}\n")
            p, r = seq.poses[f]
            q = matrix_to_quaternion(r)
            g.write(f"{fmt(t)} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")
    for name in sorted(os.listdir(args.dataset)):
        source, target = os.path.join(args.dataset, name), os.path.join(args.out, name)
        if os.path.isdir(source) and not os.path.lexists(target):
            os.symlink(os.path.abspath(source), target)
    print(f"{args.out}: {len(order)} frames ({what})")


def matrix_to_quaternion(r):
    """(qx, qy, qz, qw) of a rotation matrix (Shepperd's method)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    i = int(np.argmax([r[0, 0], r[1, 1], r[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    q[3] = (r[k, j] - r[j, k]) / s
    return tuple(q)


def cmd_score(args):
    seq = Sequence(args.out)
    kidnaps = json.load(open(os.path.join(args.out, "kidnaps.json")))["kidnaps"]
    stats = json.load(open(os.path.join(args.run_dir, "stats.json")))
    tracking, loops = stats["tracking"], stats.get("loop_closure", {})
    # Not fused: lost, or tentative (tracked from a relocalisation not yet confirmed); relocalised: the frame that
    # confirmed one (the first fused after the loss).
    verdicts = {v["frame"]: v["status"] for v in tracking.get("per_frame", [])}
    lost = {e["frame"] for e in tracking["lost"]} | {f for f, v in verdicts.items() if v == "tentative"}
    if len(lost) != tracking["lost_frames"] + tracking.get("tentative_frames", 0):
        print(f"warning: stats list {len(lost)} of {tracking['lost_frames']} lost frames (truncated list)")
    attempted = {r["frame"] for r in loops.get("relocalisation", [])}
    relocalised = {f for f, v in verdicts.items() if v == "relocalised"} if verdicts else \
        {r["frame"] for r in loops.get("relocalisation", []) if r["relocalised"]}
    est = {}
    for name in ("online", "final"):
        t, p, q = read_trajectory(os.path.join(args.run_dir, name + ".txt"))
        for ti, pi, qi in zip(t, p, q):
            f = nearest_index(seq.stamps, ti)
            if abs(seq.stamps[f] - ti) > 1e-4:
                fail(f"{args.run_dir}/{name}.txt: timestamp {ti} is no frame of {args.out}/depth.txt")
            est.setdefault(f, {})[name] = (pi, quaternion_to_matrix(qi))
    run_frames = max(est) + 1
    frames = {}   # frame -> (status, m, deg, final m) for the frames with a ground truth
    for f, e in sorted(est.items()):
        if seq.poses[f] is not None and "online" in e:
            status = "lost" if f in lost else "relocalised" if f in relocalised else "tracked"
            m, deg = difference(e["online"], seq.poses[f])
            frames[f] = (status, m, deg, difference(e["final"], seq.poses[f])[0] if "final" in e else None)

    def errors(lo, hi):
        fused = [(f, v) for f, v in frames.items() if lo <= f < hi and v[0] != "lost"]
        e = np.array([v[1] for _, v in fused]) if fused else np.zeros(0)
        final = np.array([v[3] for _, v in fused if v[3] is not None])
        false = [f for f, v in fused if v[0] == "relocalised" and (v[1] > OK_M or v[2] > OK_DEG)]
        return {"fused": len(fused), "lost": sum(1 for f in range(lo, hi) if f in lost),
                "relocalised": sum(1 for f in range(lo, hi) if f in relocalised), "false_relocalisations": false,
                "max_m": float(e.max()) if len(e) else None, "over_5cm": int((e > OK_M).sum()),
                "ate_rmse_m": float(math.sqrt(np.mean(e ** 2))) if len(e) else None,
                "ate_final_rmse_m": float(math.sqrt(np.mean(final ** 2))) if len(final) else None}

    def against_map(f, landing):
        """A relocalised frame's error against the map it was placed in: its pose seen from the fused frame before
        the landing whose true pose is nearest (the part of the map it landed on), against the same relative pose in
        the ground truth; (metres, degrees, that frame), or None. The drift of the map there moves that frame and a
        relocalisation that is right against the map alike, and cancels here."""
        mapped = [k for k in range(landing) if k in frames and frames[k][0] != "lost" and seq.poses[k] is not None]
        if not mapped or f not in est or seq.poses[f] is None:
            return None
        k = min(mapped, key=lambda j: max(difference(seq.poses[j], seq.poses[f])[0] / SEEN_M,
                                           difference(seq.poses[j], seq.poses[f])[1] / SEEN_DEG))

        def relative(a, b):   # b seen from a: (position, rotation)
            return a[1].T @ (b[0] - a[0]), a[1].T @ b[1]
        m, deg = difference(relative(est[k]["online"], est[f]["online"]), relative(seq.poses[k], seq.poses[f]))
        return m, deg, k

    def fused_off(lo, hi):
        return [f for f in range(lo, hi) if f in frames and frames[f][0] != "lost" and frames[f][1] > OK_M]

    rows = []
    for k, kid in enumerate(kidnaps):
        L = kid["landing_frame"]
        end = min(kidnaps[k + 1]["landing_frame"] if k + 1 < len(kidnaps) else run_frames, run_frames)
        row = {"kidnap": k, "landing_frame": L, "jump_m": kid["jump_m"], "jump_deg": kid["jump_deg"],
               "landing": kid["landing"], "reached": L < run_frames}
        rows.append(row)
        if not row["reached"]:
            continue
        hit = [f for f in range(L, min(L + DETECT_WITHIN + 1, end)) if f in lost or f in attempted]
        ok = [f for f in range(L, min(L + RECOVER_WITHIN + 1, end))
              if f in frames and frames[f][0] != "lost" and frames[f][1] <= OK_M and frames[f][2] <= OK_DEG]
        row.update(detected_after=hit[0] - L if hit else None, recovered_after=ok[0] - L if ok else None,
                   recovered_by=frames[ok[0]][0] if ok else None)
        if kid["landing"] == "unmapped":   # until back over a place seen before L: nothing fused > 5 cm off
            back = next((f for f in range(L, end) if seq.poses[f] is not None
                         and is_seen(nearest_seen(seq.poses, seq.poses[f], L))), end)
            row.update(back_over_map_after=back - L if back < end else None,
                       fused_off_before_back=len(fused_off(L, back)),
                       relocalised_before_back=sum(1 for f in range(L, back) if f in relocalised))
            handled = not row["fused_off_before_back"]
        else:   # recovered within 5 frames, nothing fused > 5 cm off before that
            row["fused_off_before_recovery"] = len(fused_off(L, L + (row["recovered_after"] or 0)))
            handled = row["recovered_after"] is not None and not row["fused_off_before_recovery"]
        row.update(errors(L, end))
        row["pass"] = row["detected_after"] is not None and handled and not row["false_relocalisations"]
        row["relocalised_against_map"] = [[f, *against_map(f, L)] for f in range(L, end) if f in relocalised and against_map(f, L)]
        row["false_against_map"] = [e[0] for e in row["relocalised_against_map"] if e[1] > OK_M or e[2] > OK_DEG]
    first = kidnaps[0]["landing_frame"] if kidnaps else run_frames
    summary = {"run_frames": run_frames, "before_first_kidnap": errors(0, min(first, run_frames)),
               "all": errors(0, run_frames), "alignment": "none (the run starts at frame 0's ground-truth pose)",
               "loop_closure": bool(loops.get("enabled")), "kidnaps_reached": sum(r["reached"] for r in rows),
               "detected": sum(1 for r in rows if r.get("detected_after") is not None),
               "passed": sum(1 for r in rows if r.get("pass"))}

    cm = lambda v: "-" if v is None else f"{v * 100:.1f}"  # noqa: E731
    after = lambda v: "no" if v is None else f"+{v}"  # noqa: E731
    print(f"{'#':>2} {'land':>5} {'jump cm/deg':>12} {'landing':>9} {'detect':>6} {'recover':>14} {'unmapped':>18} "
          f"{'false':>5} {'lost':>4} {'reloc':>5} {'max cm':>7} {'>5cm':>5} {'ATE cm':>6}  pass  vs map cm/deg")
    for r in rows:
        line = f"{r['kidnap']:>2} {r['landing_frame']:>5} {cm(r['jump_m']):>6}/{r['jump_deg']:<5} {r['landing']:>9}"
        if not r["reached"]:
            print(line + "  not reached")
            continue
        rec = "-" if r["recovered_by"] is None else f"{after(r['recovered_after'])} {r['recovered_by']}"
        unm = "" if r["landing"] != "unmapped" else \
            f"back {after(r['back_over_map_after'])}: {r['relocalised_before_back']}r {r['fused_off_before_back']} off"
        print(f"{line} {after(r['detected_after']):>6} {rec:>14} {unm:>18} {len(r['false_relocalisations']):>5} "
              f"{r['lost']:>4} {r['relocalised']:>5} {cm(r['max_m']):>7} {r['over_5cm']:>5} {cm(r['ate_rmse_m']):>6}  "
              f"{'yes' if r['pass'] else 'NO ':<4} "
              + " ".join(f"{cm(e[1])}/{e[2]:.1f}" for e in r["relocalised_against_map"]))
    a, b = summary["all"], summary["before_first_kidnap"]
    print(f"summary: {summary['passed']} of {len(rows)} kidnaps passed, {summary['detected']} detected "
          f"({summary['kidnaps_reached']} reached in {run_frames} frames); {a['lost']} lost, {a['relocalised']} "
          f"relocalised, {len(a['false_relocalisations'])} false; fused {a['fused']}, max {cm(a['max_m'])} cm, "
          f"{a['over_5cm']} > 5 cm; "
          f"ATE RMSE {cm(a['ate_rmse_m'])} cm online, {cm(a['ate_final_rmse_m'])} cm final (unaligned; "
          f"{cm(b['ate_rmse_m'])} cm before the first kidnap); against the map they landed on, "
          f"{sum(len(r.get('false_against_map', [])) for r in rows)} of "
          f"{sum(len(r.get('relocalised_against_map', [])) for r in rows)} relocalisations > 5 cm or 5 deg off")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            per_frame = {f: [v[0], round(v[1], 4), round(v[2], 2)] for f, v in frames.items()}   # status, m, deg
            json.dump({"out": os.path.abspath(args.out), "run_dir": os.path.abspath(args.run_dir), "kidnaps": rows,
                       "summary": summary, "frames": per_frame}, f, indent=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    make = sub.add_parser("make", help="write a dataset with frames cut out, and OUT/kidnaps.json")
    make.add_argument("dataset")
    make.add_argument("out")
    how = make.add_mutually_exclusive_group(required=True)
    how.add_argument("--cut", action="append", metavar="START:COUNT", help="cut COUNT frames from frame START")
    how.add_argument("--auto", type=int, metavar="N", help="choose N cuts")
    mirror = sub.add_parser("mirror", help="write a there-and-back sequence (frames 0..N-1, then back to 0)")
    mirror.add_argument("dataset")
    mirror.add_argument("out")
    mirror.add_argument("--frames", type=int, required=True, metavar="N", help="frames of the way there")
    mirror.add_argument("--alternate", action="store_true", help="even frames there, the odd ones between them back")
    score = sub.add_parser("score", help="score a vkmesh run on OUT")
    score.add_argument("out")
    score.add_argument("run_dir")
    score.add_argument("--json", help="write the scores here")
    args = parser.parse_args()
    try:
        {"make": cmd_make, "mirror": cmd_mirror, "score": cmd_score}[args.command](args)
    except (InputError, OSError, KeyError, ValueError) as e:
        fail(str(e))


if __name__ == "__main__":
    main()
