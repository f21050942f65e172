#!/usr/bin/env python3
"""Tests of bench/ate.py (numpy and the standard library only; run by ctest as Bench.AteEvaluator, label cpu):
  /usr/bin/python3 bench/test_ate.py        (or: /usr/bin/python3 -m pytest bench/test_ate.py)"""

import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import numpy as np

ATE_PY = Path(__file__).resolve().with_name("ate.py")
_spec = importlib.util.spec_from_file_location("ate", ATE_PY)
ate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ate)


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def quaternion(r):
    """3x3 rotation -> x y z w (unit), Shepperd's method (stable for every angle)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    i = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    if i == 0:
        s = 2 * math.sqrt(1 + trace)
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4]
    elif i == 1:
        s = 2 * math.sqrt(1 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    elif i == 2:
        s = 2 * math.sqrt(1 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    else:
        s = 2 * math.sqrt(1 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4, (r[1, 0] - r[0, 1]) / s]
    q = np.array(q)
    return q / np.linalg.norm(q)


def ground_truth(n=300, rate=30.0):
    """A smooth hand-held-like trajectory: stamps, positions (n,3), rotations (n,3,3)."""
    t = np.arange(n) / rate
    stamps = 1305031000.0 + t
    pos = np.stack([1.5 * np.sin(0.4 * t), 0.8 * np.cos(0.3 * t), 1.2 + 0.2 * np.sin(0.9 * t)], axis=1)
    rots = np.array([rotation([0.2, 1.0, 0.1], 0.5 * math.sin(0.5 * s)) @ rotation([1, 0, 0], 0.3 * s)
                     for s in t])
    return stamps, pos, rots


def write(path, stamps, pos, rots, sep=" "):
    with open(path, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for s, p, r in zip(stamps, pos, rots):
            f.write(sep.join(f"{v:.17g}" for v in [s, *p, *quaternion(r)]) + "\n")


def moved(pos, rots, r, t):
    return pos @ r.T + t, np.array([r @ q for q in rots])


class AteTest(unittest.TestCase):
    def setUp(self):
        self._dir = tempfile.TemporaryDirectory()
        self.dir = Path(self._dir.name)
        self.stamps, self.pos, self.rots = ground_truth()
        self.gt = self.dir / "gt.txt"
        write(self.gt, self.stamps, self.pos, self.rots)
        self.r = rotation([0.3, -1.0, 0.5], 1.1)
        self.t = np.array([2.0, -3.0, 0.7])

    def tearDown(self):
        self._dir.cleanup()

    def run_cli(self, *args):
        env = dict(os.environ, COLUMNS="200")  # argparse wraps --help at the terminal's width
        return subprocess.run([sys.executable, str(ATE_PY), *map(str, args)], capture_output=True, text=True,
                              env=env)

    def est(self, pos, rots, stamps=None, name="est.txt", sep=" "):
        path = self.dir / name
        write(path, self.stamps if stamps is None else stamps, pos, rots, sep)
        return path

    def test_rigid_copy_has_zero_ate_and_rpe_and_recovers_the_motion(self):
        est = self.est(*moved(self.pos, self.rots, self.r, self.t))
        out = self.dir / "out.json"
        result = self.run_cli(self.gt, est, "--json", out)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("ATE (m)", result.stdout)
        j = json.loads(out.read_text())
        self.assertEqual(j["pairs"], len(self.stamps))
        self.assertEqual(j["unmatched"], {"groundtruth": 0, "estimated": 0})
        self.assertEqual(set(j["ate"]), {"rmse", "mean", "median", "std", "min", "max"})
        self.assertLess(j["ate"]["rmse"], 1e-9)
        self.assertLess(j["ate"]["max"], 1e-9)
        self.assertEqual(j["rpe"]["delta"], 1)
        self.assertLess(j["rpe"]["trans_rmse"], 1e-9)
        self.assertLess(j["rpe"]["rot_rmse_deg"], 1e-6)
        # The alignment maps the estimate back: rotation = r^T, translation = -r^T t.
        np.testing.assert_allclose(j["alignment"]["rotation"], self.r.T, atol=1e-9)
        np.testing.assert_allclose(j["alignment"]["translation"], -self.r.T @ self.t, atol=1e-9)

    def test_noise_rmse_is_what_the_ate_reports(self):
        rng = np.random.default_rng(7)
        noise = rng.normal(0.0, 0.01, self.pos.shape)
        pos, rots = moved(self.pos + noise, self.rots, self.r, self.t)
        r = ate.evaluate(self.gt, self.est(pos, rots))
        noise_rmse = math.sqrt(np.mean(np.sum(noise ** 2, axis=1)))
        # The true motion is one candidate, so the optimum is at most the noise RMSE; fitting 6 degrees of
        # freedom to 300 points removes only a little of it.
        self.assertLessEqual(r["ate"]["rmse"], noise_rmse + 1e-12)
        self.assertGreater(r["ate"]["rmse"], 0.98 * noise_rmse)
        # Positions alone are noisy: the relative translations see it, the rotations do not.
        self.assertGreater(r["rpe"]["trans_rmse"], 0.005)
        self.assertLess(r["rpe"]["rot_rmse_deg"], 1e-6)

    def test_jitter_under_20ms_associates_and_30ms_off_does_not(self):
        rng = np.random.default_rng(3)
        jittered = self.stamps + rng.uniform(-0.015, 0.015, len(self.stamps))
        r = ate.evaluate(self.gt, self.est(*moved(self.pos, self.rots, self.r, self.t), stamps=jittered))
        self.assertEqual(r["pairs"], len(self.stamps))
        self.assertLess(r["ate"]["rmse"], 1e-9)  # every stamp found its own pose

        # 10 Hz ground truth, estimate 30 ms late: no stamp within 20 ms.
        sparse = self.dir / "gt10.txt"
        write(sparse, self.stamps[::3], self.pos[::3], self.rots[::3])
        late = self.est(self.pos[::3], self.rots[::3], stamps=self.stamps[::3] + 0.030, name="late.txt")
        result = self.run_cli(sparse, late)
        self.assertEqual(result.returncode, 2)
        self.assertIn("only 0 pose pairs associate", result.stderr)
        self.assertIn("late.txt", result.stderr)
        # ... and --offset (added to the estimated stamps) brings them back.
        result = self.run_cli(sparse, late, "--offset", "-0.03")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn(f"pairs        {len(self.stamps[::3])} associated", result.stdout)

    def test_association_is_greedy_nearest_first_each_stamp_once(self):
        gt = np.array([1.000, 1.015, 2.0])
        est = np.array([1.008, 1.012, 2.019, 2.021])
        # |dt|: (1.015, 1.012) 0.003 first; (1.015, 1.008) 0.007 then refused (1.015 used); (1.000, 1.008)
        # 0.008 kept; (2.0, 2.019) 0.019 kept; (2.0, 2.021) is 0.021 >= 0.02, never a candidate.
        self.assertEqual(ate.associate(gt, est, 0.02, 0.0), [(0, 0), (1, 1), (2, 2)])
        self.assertEqual(ate.associate(gt, est, 0.005, 0.0), [(1, 1)])

    def test_scale_is_not_aligned(self):
        # A trajectory 10% too large: a rigid alignment cannot fix it. By symmetry the best rotation is the
        # identity and the translation matches centroids, so each error is 0.1 |p - centroid|.
        centroid = self.pos.mean(axis=0)
        scaled = centroid + 1.1 * (self.pos - centroid) + np.array([0.5, 0.0, 0.0])
        r = ate.evaluate(self.gt, self.est(*moved(scaled, self.rots, self.r, self.t)))
        expected = 0.1 * np.linalg.norm(self.pos - centroid, axis=1)
        self.assertGreater(r["ate"]["rmse"], 0.01)
        self.assertAlmostEqual(r["ate"]["rmse"], math.sqrt(np.mean(expected ** 2)), delta=1e-9)
        self.assertAlmostEqual(r["ate"]["max"], expected.max(), delta=1e-9)

    def test_hand_computed_case(self):
        # ATE: a unit square against the same square 10% larger (moved rigidly): corners at (+-0.5, +-0.5) from
        # the centre become (+-0.55, +-0.55), so after alignment every error is 0.05 * sqrt(2).
        # RPE: ground truth steps 1 m along x without turning; the estimate takes the same positions but turns
        # 10 degrees about z per step. Step i: E = (I, e1)^-1 (Rz(10), Rz(-10 i) e1) = (Rz(10), Rz(-10 i) e1 - e1):
        # rotation 10 degrees, translation |Rz(-10 i) e1 - e1| = 2 sin(5 i degrees).
        square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
        gt = self.dir / "hand_gt.txt"
        write(gt, [0, 1, 2, 3], square, [np.eye(3)] * 4)
        big = (square - 0.5) * 1.1 + 0.5
        est = self.dir / "hand_est.txt"
        write(est, [0, 1, 2, 3], big @ self.r.T + self.t, [self.r] * 4)
        r = ate.evaluate(gt, est, max_dt=0.5)
        for key in ("rmse", "mean", "median", "min", "max"):
            self.assertAlmostEqual(r["ate"][key], 0.05 * math.sqrt(2), delta=1e-12, msg=key)
        self.assertAlmostEqual(r["ate"]["std"], 0.0, delta=1e-12)

        line = np.array([[i, 0, 0] for i in range(4)], float)
        write(gt, [0, 1, 2, 3], line, [np.eye(3)] * 4)
        write(est, [0, 1, 2, 3], line, [rotation([0, 0, 1], math.radians(10 * i)) for i in range(4)])
        r = ate.evaluate(gt, est, max_dt=0.5)
        self.assertLess(r["ate"]["rmse"], 1e-12)
        self.assertEqual(r["rpe"]["pairs"], 3)
        trans = [2 * math.sin(math.radians(5 * i)) for i in range(3)]
        self.assertAlmostEqual(r["rpe"]["trans_rmse"], math.sqrt(sum(x * x for x in trans) / 3), delta=1e-12)
        self.assertAlmostEqual(r["rpe"]["rot_rmse_deg"], 10.0, delta=1e-9)
        # Two frames apart: 20 degrees, translation |Rz(-10 i) 2 e1 - 2 e1| = 4 sin(5 i degrees), i = 0, 1.
        r = ate.evaluate(gt, est, max_dt=0.5, delta=2)
        self.assertEqual(r["rpe"]["pairs"], 2)
        self.assertAlmostEqual(r["rpe"]["trans_rmse"], math.sqrt((4 * math.sin(math.radians(5))) ** 2 / 2),
                               delta=1e-12)
        self.assertAlmostEqual(r["rpe"]["rot_rmse_deg"], 20.0, delta=1e-9)
        # The same step in time units.
        r2 = ate.evaluate(gt, est, max_dt=0.5, delta_seconds=2.0)
        self.assertEqual(r2["rpe"]["pairs"], 2)
        self.assertAlmostEqual(r2["rpe"]["trans_rmse"], r["rpe"]["trans_rmse"], delta=1e-15)

    def test_frame_index_stamps_and_commas(self):
        # ICL-NUIM: stamps are frame numbers; commas and comments are accepted.
        gt = self.dir / "icl_gt.txt"
        write(gt, np.arange(50), self.pos[:50], self.rots[:50], sep=",")
        est = self.dir / "icl_est.txt"
        write(est, np.arange(0, 50, 2), *moved(self.pos[:50:2], self.rots[:50:2], self.r, self.t))
        with open(est, "a") as f:
            f.write("\n   # a comment after a blank line\n")
        result = self.run_cli(gt, est, "--max-dt", "0.5")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("pairs        25 associated within 0.5", result.stdout)
        self.assertIn("unmatched: 25 ground truth, 0 estimated", result.stdout)

    def test_bad_input_names_file_and_line(self):
        est = self.est(*moved(self.pos, self.rots, self.r, self.t))
        lines = est.read_text().splitlines()
        cases = {
            "too few values": (lines[2].rsplit(" ", 1)[0], "expected 8 values"),
            "not a number": (lines[2].replace(lines[2].split()[1], "1.2.3", 1), "not a number: '1.2.3'"),
            "nan": (lines[2].replace(lines[2].split()[1], "nan", 1), "not a finite number"),
            "zero quaternion": (" ".join(lines[2].split()[:4] + ["0", "0", "0", "0"]), "quaternion"),
        }
        for name, (bad, message) in cases.items():
            with self.subTest(name):
                broken = self.dir / "broken.txt"
                broken.write_text("\n".join(lines[:2] + [bad] + lines[3:]) + "\n")
                result = self.run_cli(self.gt, broken)
                self.assertEqual(result.returncode, 2)
                self.assertIn(f"{broken}:3:", result.stderr)
                self.assertIn(message, result.stderr)
                self.assertNotIn("Traceback", result.stderr)
        result = self.run_cli(self.dir / "missing.txt", est)
        self.assertEqual(result.returncode, 2)
        self.assertIn("missing.txt: cannot read", result.stderr)

    def test_fewer_than_three_pairs_is_refused(self):
        two = self.est(self.pos[:2], self.rots[:2], stamps=self.stamps[:2], name="two.txt")
        result = self.run_cli(self.gt, two)
        self.assertEqual(result.returncode, 2)
        self.assertIn("only 2 pose pairs associate", result.stderr)
        self.assertIn("at least 3", result.stderr)

    def test_plot_is_optional(self):
        est = self.est(*moved(self.pos, self.rots, self.r, self.t))
        png = self.dir / "plot.png"
        result = self.run_cli(self.gt, est, "--plot", png)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertTrue(png.exists() or "matplotlib is not available" in result.stderr, result.stderr)

    def test_help_explains_the_time_units(self):
        result = self.run_cli("--help")
        self.assertEqual(result.returncode, 0)
        self.assertIn("frame-index", result.stdout)
        self.assertIn("0.5", result.stdout)


if __name__ == "__main__":
    unittest.main(verbosity=1)
