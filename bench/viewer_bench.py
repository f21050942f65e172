#!/usr/bin/env python3
"""The browser viewer's measurements (docs/RESULTS.md, "Viewer"; docs/VIEWER.md).

  bench/viewer_bench.py live DATASET [--voxel 0.03] [--frames N]   fusion's ms/frame with no page, one Chromium
        page, a deliberately slow page; bytes per frame on the wire; how far behind the live page is
  bench/viewer_bench.py orbit MESH.ply [--seconds 20]              the page's load time and frames per second
        orbiting the mesh in headless Chromium (SwiftShader)

Uses build/vkmesh (or $VKMESH_CLI), Debian's chromium and tests/viewer's clients. Prints one JSON object."""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "viewer"))
import browser  # noqa: E402
import wsclient  # noqa: E402

CLI = os.environ.get("VKMESH_CLI", str(ROOT / "build" / "vkmesh"))


def start(args, url_stream):
    proc = subprocess.Popen([CLI, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stream = proc.stderr if url_stream == "stderr" else proc.stdout
    while True:
        line = stream.readline()
        if not line:
            raise RuntimeError(f"no URL from vkmesh {' '.join(map(str, args))}")
        m = re.search(r"(http://[0-9.]+:(\d+)/)", line)
        if m:
            return proc, m.group(1), int(m.group(2))


def fuse(dataset, out, name, extra, page=None):
    stats = out / f"{name}.json"
    args = ["fuse", dataset, "-o", out / f"{name}.ply", "--stats", stats, "-q", *extra]
    result = {"run": name}
    if "--serve" not in extra:
        subprocess.run([CLI, *map(str, args)], check=True, capture_output=True)
    else:
        proc, url, port = start(args, "stderr")
        worker = None
        if page:
            worker = threading.Thread(target=page, args=(url, port, result))
            worker.start()
        proc.communicate()
        assert proc.returncode == 0
        if worker:
            worker.join()
    s = json.loads(stats.read_text())
    result.update(frames=s["frames"]["integrated"], triangles=s["mesh"]["triangles"],
                  wall_ms_median=s["wall_ms_per_frame"]["median"], wall_ms_mean=s["wall_ms_per_frame"]["mean"],
                  fusion_s=s["wall_s_fusion_total"], viewer=s.get("viewer"))
    return result


def live(a):
    out = Path(tempfile.mkdtemp(prefix="vkmesh-viewer-bench-"))
    common = ["--voxel", a.voxel] + (["--frames", a.frames] if a.frames else [])
    serve = common + ["--serve", 0, "--serve-linger", 0]

    def fast_client(url, port, result):
        # Reads every message as it comes: per-frame message sizes on the wire.
        c = wsclient.Client(port, timeout=600)
        sizes = []
        try:
            while True:
                op, payload = c.recv()
                if op == 8:
                    break
                h = wsclient.parse_header(payload)
                sizes.append((h["frame"], len(payload), h["coalesced"], h["flags"] & 1))
        except (ConnectionError, OSError):
            pass
        frames = [s for s in sizes if not s[3]]
        result["wire"] = {"messages": len(sizes), "join_message_bytes": sizes[0][1] if sizes else 0,
                          "frame_messages": len(frames),
                          "bytes_per_frame_median": statistics.median(s[1] for s in frames) if frames else 0,
                          "bytes_per_frame_mean": statistics.mean(s[1] for s in frames) if frames else 0,
                          "bytes_per_frame_max": max(s[1] for s in frames) if frames else 0,
                          "coalesced_messages": sum(1 for s in frames if s[2] > 1)}

    def slow_client(url, port, result):
        # A deliberately slow page: a 16 KiB receive window and 0.5 s between messages.
        c = wsclient.Client(port, rcvbuf=16384, timeout=600)
        n = 0
        try:
            while True:
                op, _ = c.recv()
                if op == 8:
                    break
                n += 1
                time.sleep(0.5)
        except (ConnectionError, OSError):
            pass
        result["slow_page_messages"] = n

    def chromium_page(url, port, result):
        with browser.Browser(url) as page:
            # Until the server goes (fusion done, linger 0): the page's count is read at each poll.
            last = None
            while True:
                try:
                    last = (page.text("vkmesh-frame"), page.text("vkmesh-triangles"), page.text("vkmesh-status"))
                except RuntimeError:
                    break
                if last[2] and last[2].startswith("disconnected"):
                    break
                time.sleep(0.5)
            result["page_last"] = last

    runs = [fuse(a.dataset, out, "no_serve", common),
            # The same GPU work as --serve (the delta passes), written to a file instead: what serving adds on top.
            fuse(a.dataset, out, "deltas_file", common + ["--deltas", out / "run.deltas"]),
            fuse(a.dataset, out, "serve_no_page", serve),
            fuse(a.dataset, out, "serve_fast_raw_client", serve, fast_client),
            fuse(a.dataset, out, "serve_slow_page", serve, slow_client),
            fuse(a.dataset, out, "serve_chromium_page", serve, chromium_page)]
    print(json.dumps({"dataset": str(a.dataset), "voxel": a.voxel, "runs": runs}, indent=1))


def orbit(a):
    proc, url, port = start(["view", a.mesh, "--port", 0, "-q"], "stdout")
    try:
        with browser.Browser(url + f"?bench={a.seconds}", width=a.width, height=a.height) as page:
            bench = page.wait_for(lambda p: p.evaluate("window.vkmeshBench || null"), a.seconds + 600, poll=1)
            print(json.dumps({"mesh": str(a.mesh), "viewport": [a.width, a.height], **(bench or {})}, indent=1))
    finally:
        proc.terminate()
        proc.wait()


def main():
    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="what", required=True)
    lp = sub.add_parser("live")
    lp.add_argument("dataset", type=Path)
    lp.add_argument("--voxel", type=float, default=0.03)
    lp.add_argument("--frames", type=int, default=0)
    op = sub.add_parser("orbit")
    op.add_argument("mesh", type=Path)
    op.add_argument("--seconds", type=float, default=20)
    op.add_argument("--width", type=int, default=1280)
    op.add_argument("--height", type=int, default=800)
    a = p.parse_args()
    live(a) if a.what == "live" else orbit(a)


if __name__ == "__main__":
    main()
