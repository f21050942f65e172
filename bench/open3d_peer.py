#!/usr/bin/python3
"""Open3D peer for vkmesh's benchmarks.

Runs Open3D's TSDF fusion (tensor VoxelBlockGrid and/or legacy ScalableTSDFVolume, CPU) on exactly the
frames vkmesh used (the JSON written by `vkmesh frames DATASET -o frames.json`) and writes per-frame
timings, extraction timings and mesh sizes as JSON. See bench/README.md for the output schema and the
choices made for comparability.

Run it with the Debian interpreter (`/usr/bin/python3`), which is where python3-open3d installs.
"""

import argparse
import json
import os
import platform
import statistics
import sys
import time

# vbg_color: the same VoxelBlockGrid with a third attribute, `color` (float32 x 3), fused from each frame's
# colour image (`color_path` in the frames JSON); the mesh it writes has vertex colours.
METHODS = ("vbg", "vbg_color", "scalable")
DEFAULT_MAX_DEPTH = 4.0
# Pre-sized VoxelBlockGrid capacity when --block-count is not given: 2^25 voxels (~256 MiB of float32
# tsdf + weight), i.e. 65536 blocks of 8^3 or 8192 blocks of 16^3. A too-small capacity is not an error
# on CPU (the hash map grows), but growing makes every later frame several times slower, which would
# benchmark Open3D's rehashing instead of its fusion.
AUTO_BLOCK_VOXELS = 1 << 25
# Share of the machine's CPU time used by other processes above which the timings get a warning.
BUSY_WARNING = 0.15


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description="Time Open3D 0.16 TSDF fusion (VoxelBlockGrid and legacy ScalableTSDFVolume, CPU) "
                    "on the frame list that vkmesh used, for side-by-side benchmarks.",
        epilog="Run with /usr/bin/python3 (Debian's python3-open3d). Output schema: bench/README.md.")
    p.add_argument("frames_json", help="frame list written by `vkmesh frames DATASET -o frames.json`")
    p.add_argument("-o", "--output", required=True, help="where to write the result JSON")
    p.add_argument("--voxel", type=float, required=True, help="voxel edge length in metres (e.g. 0.03)")
    p.add_argument("--trunc-voxels", type=float, required=True,
                   help="truncation distance in voxels; sdf_trunc = trunc_voxels * voxel (e.g. 4)")
    p.add_argument("--block-resolution", type=int, default=8, choices=(8, 16),
                   help="VoxelBlockGrid block edge in voxels (default 8, matching vkmesh's 8^3 blocks)")
    p.add_argument("--block-count", type=int, default=0,
                   help="VoxelBlockGrid pre-allocated block capacity (default: 2^25 voxels worth, i.e. "
                        "65536 blocks at resolution 8); a warning is printed if the run outgrew it")
    p.add_argument("--scalable-unit-resolution", type=int, default=16,
                   help="ScalableTSDFVolume volume_unit_resolution (default 16, Open3D's default; see README)")
    p.add_argument("--methods", default="vbg,scalable",
                   help="comma-separated subset of: %s (default: vbg,scalable; vbg_color needs frames with "
                        "color_path)" % ",".join(METHODS))
    p.add_argument("--weight-threshold", type=float, default=1.0,
                   help="VoxelBlockGrid extraction weight threshold (default 1 = 'observed at least once', "
                        "which is what the legacy volume uses; Open3D's own default is 3)")
    p.add_argument("--extract-every", type=int, default=0, metavar="N",
                   help="also time a mesh extraction after every N frames (the final one is always done)")
    p.add_argument("--warmup", type=int, default=3,
                   help="frames left out of the median integrate time (default 3)")
    p.add_argument("--max-frames", type=int, default=0,
                   help="use only the first N frames of the list (default: all)")
    p.add_argument("--negative-fy", choices=("native", "flip"), default="native",
                   help="how to pass a negative fy (ICL-NUIM): 'native' hands it to Open3D as is (it works, "
                        "see README); 'flip' uses fy' = -fy and camera_to_world' = camera_to_world * "
                        "diag(1,-1,1,1) instead, which describes the same rays (kept as a cross-check)")
    p.add_argument("--threads", type=int, default=0, metavar="N",
                   help="limit Open3D to N threads: sets OMP_NUM_THREADS and pins the process to N CPUs "
                        "before Open3D is imported (default: Open3D's own choice, all available cores)")
    p.add_argument("--mesh-out", metavar="DIR", help="write the final meshes there as open3d_<method>.ply")
    args = p.parse_args(argv)

    args.methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    bad = [m for m in args.methods if m not in METHODS]
    if bad or not args.methods:
        p.error("--methods: unknown %s (choose from %s)" % (",".join(bad) or "(empty)", ",".join(METHODS)))
    if args.voxel <= 0 or args.trunc_voxels <= 0:
        p.error("--voxel and --trunc-voxels must be positive")
    if args.block_count <= 0:
        args.block_count = AUTO_BLOCK_VOXELS // args.block_resolution ** 3
    return args


def limit_threads(n):
    """Must run before `import open3d`: libgomp reads OMP_NUM_THREADS once, when the library is loaded.

    OMP_NUM_THREADS is what actually caps Open3D 0.16's worker threads (all its CPU kernels used here are
    OpenMP loops). Pinning alone does not: with only the affinity reduced, Open3D still starts a second
    thread on a 2-CPU machine. The pinning is added so that whatever Open3D runs stays on the same N CPUs."""
    os.environ["OMP_NUM_THREADS"] = str(n)
    if hasattr(os, "sched_setaffinity"):
        cpus = sorted(os.sched_getaffinity(0))
        if n < len(cpus):
            os.sched_setaffinity(0, cpus[:n])


def cpu_jiffies():
    """(busy, total) jiffies of the whole machine from /proc/stat, or None where there is none."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    idle = v[3] + v[4]  # idle + iowait
    return sum(v) - idle, sum(v)


class OtherLoad:
    """Share of the machine's CPU time used by OTHER processes over an interval.

    Open3D's OpenMP loops slow down 10-30x (not 2x) when another process competes for the cores, so a run
    has to show whether that happened. The load average lags by a minute and counts this process too;
    /proc/stat minus this process's own CPU time does neither."""

    def __init__(self):
        self.start = cpu_jiffies()
        self.own = sum(os.times()[:2])

    def share(self):
        end = cpu_jiffies()
        if self.start is None or end is None or end[1] <= self.start[1]:
            return None
        hz = os.sysconf("SC_CLK_TCK")
        own = (sum(os.times()[:2]) - self.own) * hz
        busy = end[0] - self.start[0] - own
        return round(max(0.0, busy / (end[1] - self.start[1])), 3)


def load_frames(path, max_frames):
    with open(path) as f:
        spec = json.load(f)
    frames = spec["frames"]
    if max_frames > 0:
        frames = frames[:max_frames]
    if not frames:
        sys.exit("%s: no frames" % path)
    spec["frames"] = frames
    # null or 0 in the JSON means "no limit given"; Open3D needs a finite one.
    spec["max_depth"] = float(spec.get("max_depth") or DEFAULT_MAX_DEPTH)
    spec["depth_scale"] = float(spec["depth_scale"])
    return spec


def camera_setup(spec, negative_fy, np):
    """Returns (fx, fy, cx, cy), the per-frame world-to-camera 4x4 matrices, and what was done about fy."""
    k = spec["intrinsics"]
    fx, fy, cx, cy = (float(k[n]) for n in ("fx", "fy", "cx", "cy"))
    flip = np.eye(4)
    fy_handling = None
    if fy < 0:
        fy_handling = negative_fy
        if negative_fy == "flip":
            # Negating y_cam in the pose and fy together leaves every pixel's ray unchanged.
            flip = np.diag([1.0, -1.0, 1.0, 1.0])
            fy = -fy
    world_to_camera = []
    for fr in spec["frames"]:
        c2w = np.asarray(fr["camera_to_world"], dtype=np.float64).reshape(4, 4)
        world_to_camera.append(np.linalg.inv(c2w @ flip))
    return (fx, fy, cx, cy), world_to_camera, fy_handling


def ms_since(t0):
    return (time.perf_counter() - t0) * 1e3


def summarise(integrate_ms, warmup):
    # Too short a run to drop warm-up frames: use them all rather than report nothing.
    steady = integrate_ms[warmup:] if len(integrate_ms) > warmup else integrate_ms
    return {
        "median_ms": statistics.median(steady),
        "mean_ms": statistics.fmean(integrate_ms),
        "total_ms": sum(integrate_ms),
        "median_skips_frames": len(integrate_ms) - len(steady),
    }


def extraction_points(n_frames, every):
    """0-based frame positions after which an intermediate extraction is timed (the last one is final)."""
    if every <= 0:
        return set()
    return {i for i in range(every - 1, n_frames - 1, every)}


def run_vbg(args, spec, cam, w2c, o3d, np, color=False):
    o3c = o3d.core
    fx, fy, cx, cy = cam
    intrinsic = o3c.Tensor([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]], o3c.float64)
    extrinsics = [o3c.Tensor(e, o3c.float64) for e in w2c]
    depth_scale, depth_max, trunc = spec["depth_scale"], spec["max_depth"], args.trunc_voxels

    # Allocation of the block buffers happens here, outside any timed region.
    names, dtypes, channels = ("tsdf", "weight"), (o3c.float32, o3c.float32), ((1,), (1,))
    if color:
        names, dtypes, channels = names + ("color",), dtypes + (o3c.float32,), channels + ((3,),)
    vbg = o3d.t.geometry.VoxelBlockGrid(
        attr_names=names, attr_dtypes=dtypes, attr_channels=channels,
        voxel_size=args.voxel, block_resolution=args.block_resolution, block_count=args.block_count,
        device=o3c.Device("CPU:0"))
    frames_without_color = 0

    def extract():
        t0 = time.perf_counter()
        mesh = vbg.extract_triangle_mesh(weight_threshold=args.weight_threshold)
        ms = ms_since(t0)
        # An empty mesh has no 'positions'/'indices' attributes at all.
        nv = mesh.vertex.positions.shape[0] if "positions" in mesh.vertex else 0
        nt = mesh.triangle.indices.shape[0] if "indices" in mesh.triangle else 0
        return mesh, ms, nv, nt

    load_ms, integrate_ms, extractions = [], [], []
    checkpoints = extraction_points(len(spec["frames"]), args.extract_every)
    for i, fr in enumerate(spec["frames"]):
        t0 = time.perf_counter()
        depth = o3d.t.io.read_image(fr["depth_path"])
        load_ms.append(ms_since(t0))
        if depth.is_empty() or depth.dtype != o3c.uint16:
            sys.exit("%s: not a 16-bit depth image" % fr["depth_path"])
        rgb = None
        if color and fr.get("color_path"):
            # uint8 RGB as vkmesh's Dataset::loadColor gives it; Open3D scales it to 0..1 itself.
            rgb = o3d.t.io.read_image(fr["color_path"])
            if rgb.is_empty() or rgb.dtype != o3c.uint8 or rgb.channels != 3:
                sys.exit("%s: not an 8-bit RGB image" % fr["color_path"])
            if (rgb.rows, rgb.columns) != (depth.rows, depth.columns):
                sys.exit("%s: %dx%d, but the depth is %dx%d (colour on another grid: vkmesh resamples it with "
                         "camera.json's colour intrinsics, this peer does not)" % (
                             fr["color_path"], rgb.columns, rgb.rows, depth.columns, depth.rows))
        elif color:
            frames_without_color += 1
        load_ms[-1] = ms_since(t0)  # depth and colour reading
        extrinsic = extrinsics[i]

        t0 = time.perf_counter()
        blocks = vbg.compute_unique_block_coordinates(depth, intrinsic, extrinsic, depth_scale, depth_max, trunc)
        if rgb is not None:
            vbg.integrate(blocks, depth, rgb, intrinsic, extrinsic, depth_scale, depth_max, trunc)
        else:
            vbg.integrate(blocks, depth, intrinsic, extrinsic, depth_scale, depth_max, trunc)
        integrate_ms.append(ms_since(t0))

        if i in checkpoints:
            _, ms, nv, nt = extract()
            extractions.append({"after_frames": i + 1, "ms": ms, "vertices": nv, "triangles": nt})

    mesh, ms, nv, nt = extract()
    extractions.append({"after_frames": len(spec["frames"]), "ms": ms, "vertices": nv, "triangles": nt})
    hashmap = vbg.hashmap()
    legacy = mesh.to_legacy() if nv else None
    if legacy is not None and color and legacy.has_vertex_colors():
        # Legacy meshes hold colours in 0..1 (written as uchar 0..255); guard against a 0..255 grid.
        c = np.asarray(legacy.vertex_colors)
        if c.size and c.max() > 1.0 + 1e-6:
            legacy.vertex_colors = o3d.utility.Vector3dVector(np.clip(c / 255.0, 0.0, 1.0))
    result = {
        "api": "open3d.t.geometry.VoxelBlockGrid (CPU:0)" + (", attribute color" if color else ""),
        "block_resolution": args.block_resolution,
        "block_count": args.block_count,
        "block_count_exceeded": hashmap.size() > args.block_count,
        "weight_threshold": args.weight_threshold,
        "blocks": hashmap.size(),
        "integrate_ms": integrate_ms,
        "load_ms": load_ms,
        **summarise(integrate_ms, args.warmup),
        "extract_ms": ms,
        "vertices": nv,
        "triangles": nt,
        "extractions": extractions,
    }
    if color:
        result["frames_without_color"] = frames_without_color
    return result, legacy


def run_scalable(args, spec, cam, w2c, o3d, np):
    k = spec["intrinsics"]
    width, height = int(k["width"]), int(k["height"])
    fx, fy, cx, cy = cam
    intrinsic = o3d.camera.PinholeCameraIntrinsic(width, height, fx, fy, cx, cy)
    vol = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=args.voxel, sdf_trunc=args.trunc_voxels * args.voxel,
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.NoColor,
        volume_unit_resolution=args.scalable_unit_resolution)
    # The legacy API only integrates RGBDImages. With NoColor the colour is never read, so one shared
    # grey image is enough; building the RGBDImage (which also converts depth to float metres and applies
    # depth_trunc) is timed as part of preparation, not integration.
    grey = o3d.geometry.Image(np.full((height, width, 3), 128, dtype=np.uint8))

    def extract():
        t0 = time.perf_counter()
        mesh = vol.extract_triangle_mesh()
        ms = ms_since(t0)
        return mesh, ms, len(mesh.vertices), len(mesh.triangles)

    prep_ms, integrate_ms, extractions = [], [], []
    checkpoints = extraction_points(len(spec["frames"]), args.extract_every)
    for i, fr in enumerate(spec["frames"]):
        t0 = time.perf_counter()
        depth = o3d.io.read_image(fr["depth_path"])
        if depth.is_empty() or np.asarray(depth).dtype != np.uint16:
            sys.exit("%s: not a 16-bit depth image" % fr["depth_path"])
        if np.asarray(depth).shape != (height, width):
            sys.exit("%s: size does not match the intrinsics' %dx%d" % (fr["depth_path"], width, height))
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            grey, depth, depth_scale=spec["depth_scale"], depth_trunc=spec["max_depth"],
            convert_rgb_to_intensity=False)
        prep_ms.append(ms_since(t0))

        t0 = time.perf_counter()
        vol.integrate(rgbd, intrinsic, w2c[i])
        integrate_ms.append(ms_since(t0))

        if i in checkpoints:
            _, ms, nv, nt = extract()
            extractions.append({"after_frames": i + 1, "ms": ms, "vertices": nv, "triangles": nt})

    mesh, ms, nv, nt = extract()
    extractions.append({"after_frames": len(spec["frames"]), "ms": ms, "vertices": nv, "triangles": nt})
    result = {
        "api": "open3d.pipelines.integration.ScalableTSDFVolume (legacy, NoColor)",
        "volume_unit_resolution": args.scalable_unit_resolution,
        "blocks": None,  # the legacy volume does not expose its number of volume units
        "integrate_ms": integrate_ms,
        "load_ms": prep_ms,
        **summarise(integrate_ms, args.warmup),
        "extract_ms": ms,
        "vertices": nv,
        "triangles": nt,
        "extractions": extractions,
    }
    return result, (mesh if nv else None)


def print_summary(out):
    th = out["threads"]
    print("Open3D %s | %s (%s), %d frames | voxel %.4g m, trunc %.4g voxels, max depth %.3g m | "
          "threads: %s of %d CPUs" % (
              out["open3d_version"], os.path.basename(out["dataset"].rstrip("/")) or out["dataset"],
              out["kind"], out["num_frames"], out["voxel"], out["trunc_voxels"], out["max_depth"],
              th["requested"] or "all %d usable" % th["usable_cpus"], th["cpu_count"]))
    if out["negative_fy"]:
        print("negative fy passed as: %s" % out["negative_fy"])
    print("%-9s %14s %10s %11s %10s %10s %7s" % (
        "method", "integ. median", "mean", "extract", "vertices", "triangles", "blocks"))
    for name, r in out["methods"].items():
        print("%-9s %11.2f ms %7.2f ms %8.1f ms %10d %10d %7s" % (
            name, r["median_ms"], r["mean_ms"], r["extract_ms"], r["vertices"], r["triangles"],
            "-" if r["blocks"] is None else r["blocks"]))
        if r.get("block_count_exceeded"):
            print("  WARNING: %s outgrew --block-count %d (%d blocks); its timings include hash-map "
                  "growth, rerun with a larger --block-count" % (name, r["block_count"], r["blocks"]))
    print("(median skips the first %d frames; mean is over all frames; depth loading not included)"
          % out["warmup_frames"])
    shares = [x for x in (out["other_cpu_share_before"], out["other_cpu_share_during"]) if x is not None]
    if shares and max(shares) > BUSY_WARNING:
        print("WARNING: other processes used %.0f%% of the machine's CPU time before/during the run; "
              "Open3D's timings are then not representative, rerun on an idle machine" % (100 * max(shares)))


def main(argv=None):
    args = parse_args(argv)
    if args.threads > 0:
        limit_threads(args.threads)
    # Imported only now so that --threads can take effect (see limit_threads).
    import numpy as np
    import open3d as o3d

    spec = load_frames(args.frames_json, args.max_frames)
    # Half a second of looking at the machine before starting catches a concurrent build that is
    # already running; `during` catches one that starts mid-run.
    probe = OtherLoad()
    time.sleep(0.5)
    before = probe.share()
    during = OtherLoad()
    cam, w2c, fy_handling = camera_setup(spec, args.negative_fy, np)
    out = {
        "tool": "bench/open3d_peer.py",
        "open3d_version": o3d.__version__,
        "python": platform.python_version(),
        "frames_json": os.path.abspath(args.frames_json),
        "dataset": spec.get("dataset", ""),
        "kind": spec.get("kind", ""),
        "num_frames": len(spec["frames"]),
        "frame_indices": [fr.get("index") for fr in spec["frames"]],
        "voxel": args.voxel,
        "trunc_voxels": args.trunc_voxels,
        "sdf_trunc": args.voxel * args.trunc_voxels,
        "depth_scale": spec["depth_scale"],
        "max_depth": spec["max_depth"],
        "intrinsics": spec["intrinsics"],
        "negative_fy": fy_handling,
        "warmup_frames": args.warmup,
        "threads": {
            "cpu_count": os.cpu_count(),
            "usable_cpus": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
            "requested": args.threads or None,
            "OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS"),
        },
        "other_cpu_share_before": before,
        "methods": {},
    }
    runners = {"vbg": run_vbg, "scalable": run_scalable,
               "vbg_color": lambda *a: run_vbg(*a, color=True)}
    for name in args.methods:
        result, mesh = runners[name](args, spec, cam, w2c, o3d, np)
        if args.mesh_out and mesh is not None:
            os.makedirs(args.mesh_out, exist_ok=True)
            path = os.path.join(args.mesh_out, "open3d_%s.ply" % name)
            o3d.io.write_triangle_mesh(path, mesh)
            result["mesh_path"] = os.path.abspath(path)
        out["methods"][name] = result

    out["other_cpu_share_during"] = during.share()
    with open(args.output, "w") as f:
        json.dump(out, f, indent=1)
    print_summary(out)


if __name__ == "__main__":
    main()
