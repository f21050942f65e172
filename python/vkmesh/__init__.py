"""vkmesh: real-time 3D reconstruction on any Vulkan device, from Python.

Depth frames with known camera poses are fused into a TSDF on a hashed block grid on the GPU, and one
incremental triangle mesh is kept up to date every frame (Dong et al., ICRA 2018). numpy arrays in, numpy
arrays out; the work is done by the C++ library (vkmesh::Reconstructor), with the GIL released.

    import vkmesh
    vkmesh.synth("room", frames=60)                      # a synthetic sequence with ground truth
    r = vkmesh.Reconstructor(voxel_size=0.03)            # the defaults of `vkmesh fuse`
    for f in vkmesh.open_dataset("room"):
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    m = r.mesh()                                         # m.vertices (N, 3) float32, m.triangles (M, 3) uint32
    m.save("room.ply")

Contents: Reconstructor, Mesh, MeshDelta, open_dataset (Dataset, Frame), read_mesh, merge_maps, list_tiles,
merge_tiles, devices (Device),
synth, validation_messages, Error, CapacityWarning. docs/PYTHON.md in the source tree has more.
"""

import os
import warnings
from typing import Iterator, List, NamedTuple, Optional, Tuple

import numpy as np

# A wheel (`pip install .`) carries vkmesh's data files (camera presets) in vkmesh/data; the compiled module finds
# them through VKMESH_DATA_DIR. A build-tree or CMake-installed module has none there and finds them as before.
if os.path.isdir(os.path.join(os.path.dirname(__file__), "data", "cameras")):
    os.environ.setdefault("VKMESH_DATA_DIR", os.path.join(os.path.dirname(__file__), "data"))

from . import _vkmesh  # noqa: E402
from ._vkmesh import CapacityWarning, Error, Reconstructor  # noqa: E402

Reconstructor.__module__ = "vkmesh"   # as help() and tracebacks name it (the class lives in vkmesh._vkmesh)

__version__ = "0.1.0"
__all__ = [
    "Reconstructor", "Mesh", "MeshDelta", "Dataset", "Frame", "Device", "open_dataset", "read_mesh", "merge_maps",
    "list_tiles", "merge_tiles", "register_maps", "optimise_pose_graph", "devices", "synth", "validation_messages", "Error", "CapacityWarning", "ADDED", "CHANGED", "REMOVED",
]

# MeshDelta kinds (docs/DELTAS.md), the GPU's own values.
ADDED, CHANGED, REMOVED = _vkmesh._DELTA_ADDED, _vkmesh._DELTA_CHANGED, _vkmesh._DELTA_REMOVED


def _shape(a) -> str:
    return str(tuple(a.shape))


class Mesh:
    """An indexed triangle mesh: what Reconstructor.mesh() and read_mesh() return, and what save() writes.

    vertices   (N, 3) float32 positions in metres (world frame)
    triangles  (M, 3) uint32 vertex indices, counter-clockwise seen from outside
    normals    (N, 3) float32 unit normals, or None
    colors     (N, 3) uint8 red, green, blue, or None (no colour fused)
    ages       (N,) uint32 frames since each vertex was created, or None

    Mesh(vertices, triangles, normals=None, colors=None, ages=None) builds one from array-likes: positions and
    normals are converted to float32, indices to uint32 (they must be in range); colours must already be uint8
    (Open3D's float colours in [0, 1]: (numpy.asarray(c) * 255).round().astype(numpy.uint8)).
    """

    __slots__ = ("vertices", "triangles", "normals", "colors", "ages")

    def __init__(self, vertices, triangles, normals=None, colors=None, ages=None):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            raise ValueError(f"vertices must be an N x 3 array, got shape {_shape(self.vertices)}")
        n = len(self.vertices)
        t = np.asarray(triangles)
        if t.size == 0:
            t = t.reshape(0, 3)
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"triangles must be an M x 3 array of vertex indices, got shape {_shape(t)}")
        if t.size and not np.issubdtype(t.dtype, np.integer):
            raise ValueError(f"triangles must hold integer vertex indices, got dtype {t.dtype}")
        if t.size and (t.min() < 0 or t.max() >= n):
            raise ValueError(f"triangles index vertices {t.min()}..{t.max()} but there are {n} vertices")
        self.triangles = np.ascontiguousarray(t, dtype=np.uint32)
        self.normals = None if normals is None else np.ascontiguousarray(normals, dtype=np.float32)
        if self.normals is not None and self.normals.shape != (n, 3):
            raise ValueError(f"normals must be {n} x 3 (one per vertex), got shape {_shape(self.normals)}")
        self.colors = None if colors is None else np.ascontiguousarray(colors)
        if self.colors is not None:
            if self.colors.dtype != np.uint8:
                raise ValueError(f"colors must be uint8 (red, green, blue in 0..255), got dtype {self.colors.dtype}")
            if self.colors.shape != (n, 3):
                raise ValueError(f"colors must be {n} x 3 (one per vertex), got shape {_shape(self.colors)}")
        self.ages = None if ages is None else np.ascontiguousarray(ages)
        if self.ages is not None:
            if not np.issubdtype(self.ages.dtype, np.integer) or self.ages.shape != (n,) or (n and self.ages.min() < 0):
                raise ValueError(f"ages must be {n} non-negative integers (one per vertex), got dtype {self.ages.dtype} "
                                 f"and shape {_shape(self.ages)}")
            self.ages = self.ages.astype(np.uint32, copy=False)

    def save(self, path, simplify=None):
        """Writes the mesh as binary PLY (with normals, colours and ages when present), as OBJ when the path ends
        in .obj, or as binary glTF 2.0 when it ends in .glb (Blender, three.js, Unity), exactly as `vkmesh fuse -o`
        writes its meshes; any other extension raises vkmesh.Error. simplify=RATIO (0 < RATIO <= 1) writes a
        simplified copy with about that fraction of the triangles (meshoptimizer; this Mesh is not changed) and
        returns {"ratio", "triangles_before", "triangles_after", "error_m"}: error_m is the geometric error
        meshoptimizer reports, in metres. Without simplify, returns None."""
        return _vkmesh._write_mesh(os.fspath(path), self.vertices, self.triangles, self.normals, self.colors, self.ages,
                                   simplify)

    def __repr__(self) -> str:
        extras = [name for name in ("normals", "colors", "ages") if getattr(self, name) is not None]
        return (f"<vkmesh.Mesh {len(self.vertices)} vertices, {len(self.triangles)} triangles"
                + (", with " + ", ".join(extras) if extras else "") + ">")


def read_mesh(path) -> Mesh:
    """Reads a PLY file (ascii or binary; what `vkmesh fuse -o mesh.ply` writes, and most tools' PLY), or a
    binary glTF file when the path ends in .glb, into a Mesh: positions, triangles (polygons split into fans),
    and normals, colours and ages when the file has them. Raises vkmesh.Error naming the file for a missing,
    corrupt or unsupported one."""
    return _vkmesh._read_mesh(os.fspath(path))


def merge_maps(inputs, output, *, mesh=None, keep_frames: bool = True, frames_budget_mb: float = 1024,
               frames_spill=None, device=None, validation: bool = False, tiles=None, tile_size: float = 0,
               register: bool = False) -> dict:
    """Adds saved maps into one, as `vkmesh merge INPUTS... -o OUTPUT` does (docs/SCALING.md): maps fused from parts
    of one recording (or from recordings of one place in one world frame) add up to the map of all their frames. The
    TSDF sums and counts are added corner by corner, blocks united, colours combined by their weights, and the mesh is
    built from the sum: the mesh one run fusing every frame would have. Returns the statistics `vkmesh merge --stats`
    writes, as a dict: inputs (path, blocks, frames_integrated, frame_store, frames_stored of each), blocks (merged,
    shared), observed_corners, frames_integrated, frame_store (path, frames, renumbered), mesh (vertices, triangles),
    ms (read, merge, rebuild, save), warnings (each also given to warnings.warn); plus output (the merged map's path)
    and, with `mesh`, mesh["path"].

    inputs            paths of maps (.vkmap) saved by Reconstructor.save() or `vkmesh fuse --save` with the same
                      settings (voxel size, truncation, depth range, colour mode, ...)
    output            the merged map (.vkmap); Reconstructor.load(output) and `vkmesh fuse --load` continue it
    mesh              None, or a path to write the merged mesh to (.ply, .obj or .glb, as Mesh.save writes them; an
                      extension vkmesh cannot write raises vkmesh.Error before anything is merged)
    keep_frames       carry the frame stores saved beside the inputs (INPUT.vkframes) over into OUTPUT.vkframes, so
                      that the merged map can be corrected (docs/CORRECTION.md); frame indices that collide between
                      inputs are renumbered (frame_store["renumbered"]). False: like --no-frames
    frames_budget_mb, frames_spill   the merged frame store's memory budget in MiB (1024) and a folder for the frames
                      beyond it (None: none, and a store past the budget raises vkmesh.Error) (--frames-budget,
                      --frames-spill)
    device            None (a discrete GPU if any, else the first suitable device) or an index from devices()
    validation        the Khronos validation layer (also on with VKMESH_VALIDATION=1)
    tiles, tile_size  a folder and a size in metres: the mesh also written tile by tile (tile_X_Y_Z.ply; each tile
                      meshed alone on the GPU; joined by vertex position they are the mesh, no seam) as
                      `vkmesh merge --tiles DIR --tile-size S`; output may then be None (tiles only). stats["tiles"]:
                      count, triangles, max_blocks
    register          the maps are sessions of one place, each in the world frame of its own first pose (each tracked
                      on its own): each later map is registered to the first by the frames their stores keep, its frames
                      fused there, and the maps added, as `vkmesh merge --register` (docs/SCALING.md, "Sessions of one
                      place"). stats["registration"]: per later map the transform and the keyframe pairs tried, verified
                      and agreeing. Maps that cannot be registered surely raise vkmesh.Error saying what was tried

    Maps that do not add up (other settings, bounded maps, a corner past its count) raise vkmesh.Error naming the
    file and what differs ("b.vkmap: fused with voxel size 0.05 but a.vkmap with 0.04 (--voxel); ..."); nothing is
    written then. The maps are read and added on the host before a device is opened; the GIL is released meanwhile.
    """
    if isinstance(inputs, (str, bytes, os.PathLike)):
        raise TypeError("inputs must be a list of map paths, not one path")
    paths = [os.fspath(p) for p in inputs]
    if not paths:
        raise ValueError("merge_maps: no maps given (inputs is empty)")
    mesh_path = None if mesh is None else os.fspath(mesh)
    if mesh_path is not None:
        _vkmesh._check_mesh_path(mesh_path)   # a mesh vkmesh cannot write fails now, not after the merge
    if not (np.isfinite(frames_budget_mb) and frames_budget_mb > 0):
        raise ValueError(f"frames_budget_mb {frames_budget_mb} must be a positive finite number")
    if (tiles is None) != (not tile_size):
        raise ValueError("tiles (a folder) and tile_size (metres) go together")
    if output is None and tiles is None:
        raise ValueError("merge_maps: output is None and no tiles are asked for: nothing to write")
    if output is None and mesh_path is not None:
        raise ValueError("merge_maps: mesh needs an output map (without one there are only tiles)")
    out = "" if output is None else os.fspath(output)
    stats, merged = _vkmesh._merge_maps(paths, out, bool(keep_frames), float(frames_budget_mb),
                                        "" if frames_spill is None else os.fspath(frames_spill), device, bool(validation),
                                        mesh_path is not None, float(tile_size or 0), "" if tiles is None else os.fspath(tiles),
                                        bool(register))
    for w in stats["warnings"]:
        warnings.warn(f"merge_maps: {w}", stacklevel=2)   # what `vkmesh merge` prints as warnings
    stats["output"] = out or None
    if tiles is not None:
        stats["tiles"]["path"] = os.fspath(tiles)
        stats["tiles"]["size_m"] = float(tile_size)
    if mesh_path is not None:
        merged.save(mesh_path)
        stats["mesh"]["path"] = mesh_path
    return stats


def list_tiles(inputs, tile_size: float) -> dict:
    """The tiles of the sum of saved maps, from their block tables alone (no corner is read; docs/SCALING.md,
    "Tiles on separate workers"): {"tiles": [(x, y, z), ...] (every tile holding a block of the sum, in order; a
    tile's key is the metres of its lower corner divided by tile_size), "blocks": the sum's blocks,
    "frames_integrated": the sum's frames}. The maps are
    checked to add up (settings, bounded maps, colour mode): vkmesh.Error naming the file otherwise."""
    if isinstance(inputs, (str, bytes, os.PathLike)):
        raise TypeError("inputs must be a list of map paths, not one path")
    return _vkmesh._list_tiles([os.fspath(p) for p in inputs], float(tile_size))


def merge_tiles(inputs, tiles_dir, tile_size: float, *, tiles=None, device=None, validation: bool = False) -> dict:
    """Makes tiles of the sum of saved maps, each from the blocks it needs read from every input (its own and one
    block around them), never the whole map: what a worker of a tiled merge runs (vkmesh.batch --tiles; C++
    vkmesh::mergeTiles, src/api/map_merge.h). Each tile is added, meshed alone on the GPU and cut to its own cubes'
    triangles: the tile `merge_maps(tiles=..., tile_size=...)` writes from the whole sum, bit for bit, and the tiles
    joined by vertex position are the mesh of the sum (no seam, no vertex twice).

    inputs     paths of maps (.vkmap) that add up (as for merge_maps)
    tiles_dir  the folder the tiles are written to, tile_X_Y_Z.ply (each under a temporary name, then renamed: a tile
               file is whole or absent); created if missing
    tile_size  the tiles' side in metres (> 0)
    tiles      the tiles to make, (x, y, z) keys as list_tiles gives them; None: every tile of the sum
    device, validation   as for merge_maps

    Returns {"tiles": [{"tile", "path" (None: no triangle, nothing written), "blocks_read", "blocks_meshed",
    "vertices", "triangles", "ms": {"read", "mesh"}}, ...], "count" (tiles written), "triangles",
    "max_blocks_host" (the most blocks of corners in host memory at once: those read for one tile and their sum),
    "max_blocks_gpu" (the most on the GPU), "table_blocks" (the inputs' block tables, 16 bytes a block),
    "ms": {"open"}}. Maps that do not add up raise vkmesh.Error naming the file; the GIL is released meanwhile."""
    if isinstance(inputs, (str, bytes, os.PathLike)):
        raise TypeError("inputs must be a list of map paths, not one path")
    keys = None
    if tiles is not None:
        keys = []
        for t in tiles:
            if len(t) != 3:
                raise ValueError(f"tiles: {t!r} is not an (x, y, z) tile key")
            keys.append(tuple(int(v) for v in t))
    return _vkmesh._merge_tiles([os.fspath(p) for p in inputs], os.fspath(tiles_dir), float(tile_size), keys, device,
                                bool(validation))


def register_maps(first, second) -> dict:
    """The transform that takes the second saved map's world into the first's, found from the frames both keep (their
    .vkframes beside them: maps saved by a Reconstructor(keep_frames=True)); C++ slam::registerSessions
    (src/slam/session_registration.h): keyframes recognised by their random-fern codes, registered by ICP, verified
    as loops are, and answered by what several verified pairs agree on. What vkmesh.batch --loop-closure runs between
    fragments that revisit a place.

    Returns {"transform": 4 x 4 nested list (a point of the second map's world, times it, is in the first's),
    "pairs_registered", "pairs_verified", "pairs_agreeing", "spread_m", "spread_degrees" (the furthest an agreeing
    pair's transform lies from the answer), "keyframes": (the first's, the second's), "ms"}. Raises vkmesh.Error when
    a map has no frame store beside it, or when the registration is not sure (too few pairs agree, no overlap, or two
    places agree on different transforms), saying what was tried. The GIL is released meanwhile."""
    return _vkmesh._register_maps(os.fspath(first), os.fspath(second))


def _pose16(pose, what):
    a = np.asarray(pose, dtype=np.float64)
    if a.size != 16:
        raise ValueError(f"{what} must be a 4 x 4 pose (or 16 numbers, row-major), got shape {a.shape}")
    return a.reshape(16).tolist()


def optimise_pose_graph(poses, edges, *, huber: float = 1.0, max_iterations: int = 50) -> dict:
    """Least-squares fit of poses to relative-pose edges (C++ slam::PoseGraph, Ceres; src/slam/pose_graph.h). Node 0
    is held fixed.

    poses  list of 4 x 4 poses (node k's transform into the world), the starting guess
    edges  list of {"from": i, "to": j, "measured": 4 x 4, inverse(pose[i]) @ pose[j] as measured,
           "sigma_m": its translation's standard deviation (metres), "sigma_deg": its rotation's (degrees),
           "loop": bool (loop edges take a Huber loss of width `huber` standard deviations)}

    Returns {"poses": the optimised 4 x 4 poses (nested lists), "converged", "iterations", "initial_cost",
    "final_cost", "edge_errors": each edge's whitened residual's length at the solution (how many standard deviations
    it is off: a large one is an edge that disagrees with the others), "ms"}. Deterministic (one thread)."""
    nodes = [_pose16(p, f"poses[{k}]") for k, p in enumerate(poses)]
    if not nodes:
        raise ValueError("optimise_pose_graph: no poses given")
    checked = []
    for k, e in enumerate(edges):
        missing = {"from", "to", "measured", "sigma_m", "sigma_deg"} - set(e)
        if missing:
            raise ValueError(f"edges[{k}] lacks {sorted(missing)}")
        checked.append({"from": int(e["from"]), "to": int(e["to"]), "measured": _pose16(e["measured"], f"edges[{k}]['measured']"),
                        "sigma_m": float(e["sigma_m"]), "sigma_deg": float(e["sigma_deg"]), "loop": bool(e.get("loop", False))})
    return _vkmesh._optimise_pose_graph(nodes, checked, float(huber), int(max_iterations))


class MeshDelta:
    """One frame's mesh changes (Reconstructor.deltas(), docs/DELTAS.md).

    frame                  the frame number (1 = the first integrated frame)
    vertex_ids             (K,) uint32: vertex ids (stable while the vertex lives, reused afterwards)
    vertex_kinds           (K,) uint8: vkmesh.ADDED, vkmesh.CHANGED (moved, new normal or colour) or vkmesh.REMOVED
    vertex_positions       (K, 3) float32, vertex_normals (K, 3) float32, vertex_created_frames (K,) uint32,
    vertex_colors          (K, 4) uint8 red, green, blue, alpha (alpha 0: no colour): meaningful for ADDED
                           and CHANGED
    triangle_ids           (T,) uint32, triangle_kinds (T,) uint8 (ADDED or REMOVED)
    triangle_vertices      (T, 3) uint32 vertex ids of ADDED triangles

    Applying a frame to a copy of the mesh: removals first, then additions and changes.
    """

    __slots__ = ("frame", "vertex_ids", "vertex_kinds", "vertex_positions", "vertex_normals", "vertex_created_frames",
                 "vertex_colors", "triangle_ids", "triangle_kinds", "triangle_vertices")

    def __init__(self, **fields):
        for name in self.__slots__:
            setattr(self, name, fields[name])

    def __repr__(self) -> str:
        def counts(kinds):
            return "/".join(str(int(np.count_nonzero(kinds == k))) for k in (ADDED, CHANGED, REMOVED))
        return (f"<vkmesh.MeshDelta frame {self.frame}: vertices added/changed/removed {counts(self.vertex_kinds)}, "
                f"triangles {counts(self.triangle_kinds)}>")


class Frame:
    """One frame of a Dataset.

    index        position in the dataset
    timestamp    seconds (TUM), frame index (ICL-NUIM) or frame number (Redwood, 7-Scenes)
    depth        (H, W) float32 metres, 0 = no measurement (the files' raw values / depth_scale, exactly as
                 `vkmesh fuse` computes them)
    color        (H, W, 3) uint8 red, green, blue registered to depth, or None
    pose         (4, 4) float64 camera-to-world, or None where the dataset has none (open_dataset with
                 require_poses=False): Reconstructor.integrate(depth, intrinsics, None) tracks the camera
    intrinsics   (fx, fy, cx, cy)
    depth_scale  raw depth units per metre in the files
    depth_path, color_path   the files ("" when there is no colour image)
    """

    __slots__ = ("index", "timestamp", "depth", "color", "pose", "intrinsics", "depth_scale", "depth_path", "color_path")

    def __init__(self, **fields):
        for name in self.__slots__:
            setattr(self, name, fields[name])

    def __repr__(self) -> str:
        h, w = self.depth.shape
        return (f"<vkmesh.Frame {self.index} ({w}x{h}{', colour' if self.color is not None else ''}) "
                f"from {self.depth_path}>")


class Dataset:
    """A depth sequence on disk (TUM RGB-D, ICL-NUIM, Redwood or 7-Scenes layout), opened by open_dataset().

    len(ds) frames; ds[i] loads frame i (raises vkmesh.Error if its depth image is unreadable); iterating
    yields the frames `vkmesh fuse` would fuse, in order: a frame whose depth image cannot be read, or which has
    no valid depth, is skipped with a warning (warnings.warn), as the CLI skips it.
    Properties: path, kind, intrinsics (fx, fy, cx, cy), width, height, depth_scale, has_color, warnings (notes
    from opening it: frames without a pose, default intrinsics used, ...).
    """

    def __init__(self, impl):
        self._impl = impl

    def __len__(self) -> int:
        return len(self._impl)

    def __getitem__(self, index: int) -> Frame:
        n = len(self._impl)
        if not isinstance(index, (int, np.integer)):
            raise TypeError(f"dataset indices are integers, not {type(index).__name__}")
        i = int(index) + n if index < 0 else int(index)
        if not 0 <= i < n:
            raise IndexError(f"frame {index} out of range: the dataset has {n} frames")
        return self._frame(i)[0]

    def _frame(self, i: int) -> Tuple[Frame, str]:
        d = self._impl.load(i)
        frame = Frame(index=d["index"], timestamp=d["timestamp"], depth=d["depth"], color=d["color"], pose=d["pose"],
                      intrinsics=self._impl.intrinsics, depth_scale=self._impl.depth_scale, depth_path=d["depth_path"],
                      color_path=d["color_path"])
        return frame, d["color_warning"]

    def __iter__(self) -> Iterator[Frame]:
        for i in range(len(self._impl)):
            try:
                frame, color_warning = self._frame(i)
            except Error as e:
                warnings.warn(f"frame {i} skipped: {e}", stacklevel=2)
                continue
            if not np.any(frame.depth > 0):
                warnings.warn(f"frame {i} skipped: no valid depth in {frame.depth_path}", stacklevel=2)
                continue
            if color_warning:
                warnings.warn(f"frame {i} fused without colour: {color_warning}", stacklevel=2)
            yield frame

    path = property(lambda self: self._impl.folder, doc="The dataset's folder (absolute).")
    kind = property(lambda self: self._impl.kind, doc="'TUM RGB-D', 'ICL-NUIM', 'Redwood' or '7-Scenes'.")
    intrinsics = property(lambda self: self._impl.intrinsics, doc="(fx, fy, cx, cy) of the depth camera.")
    width = property(lambda self: self._impl.width, doc="Depth image width in pixels.")
    height = property(lambda self: self._impl.height, doc="Depth image height in pixels.")
    depth_scale = property(lambda self: self._impl.depth_scale, doc="Raw depth units per metre in the files.")
    has_color = property(lambda self: self._impl.has_color, doc="Whether any frame has a colour image.")
    warnings = property(lambda self: list(self._impl.warnings), doc="Notes from opening the dataset.")

    def __repr__(self) -> str:
        return f"<vkmesh.Dataset {self.kind}, {len(self)} frames of {self.width}x{self.height} in {self.path}>"


def open_dataset(path, frames: int = 0, intrinsics=None, depth_scale: Optional[float] = None,
                 max_depth: float = 0.0, require_poses: bool = True, *, depth_topic: str = "",
                 color_topic: str = "", info_topic: str = "") -> Dataset:
    """Opens a depth sequence: a folder in TUM RGB-D, ICL-NUIM, Redwood or 7-Scenes layout, or a recording
    (ROS 1 bag, RealSense bag, MCAP, rosbag2), detected as `vkmesh fuse` detects it (README.md lists what each
    layout needs; docs/RECORDINGS.md the recordings).

    frames       use at most this many frames (0: all), like --frames
    intrinsics   (fx, fy, cx, cy) overriding the dataset's, like --intrinsics
    depth_scale  raw units per metre overriding the dataset's, like --depth-scale
    max_depth    metres beyond which a frame's depth is set to 0 (0: no limit). The Reconstructor ignores
                 depth beyond its own max_depth anyway, so this is rarely needed.
    require_poses  False: a sequence without poses opens too (as `vkmesh fuse --track`), and every listed
                 frame is kept; a frame without a pose has pose None (docs/TRACKING.md)
    depth_topic, color_topic, info_topic  recordings: the topics to read, like --depth-topic, --color-topic,
                 --info-topic (default: chosen by message type)

    Raises vkmesh.Error naming the file or value at fault for a folder it cannot use.
    """
    if frames < 0:
        raise ValueError(f"frames {frames} must be >= 0 (0 = all)")
    if depth_scale is not None and not (np.isfinite(depth_scale) and depth_scale > 0):
        raise ValueError(f"depth_scale {depth_scale} must be a positive finite number")
    if not (np.isfinite(max_depth) and max_depth >= 0):
        raise ValueError(f"max_depth {max_depth} must be a finite number >= 0 (0 = no limit)")
    return Dataset(_vkmesh._Dataset(os.fspath(path), int(frames), float(max_depth), intrinsics, depth_scale,
                                    bool(require_poses), str(depth_topic), str(color_topic), str(info_topic)))


class Device(NamedTuple):
    """A Vulkan device (vkmesh.devices()). Pass its index as Reconstructor(device=...)."""
    index: int
    name: str
    type: str            # "discrete GPU", "integrated GPU", "CPU", ...
    api_version: str
    driver: str
    suitable: bool       # whether vkmesh can run on it
    why_not: str         # what it lacks when not suitable
    int64_atomics: bool  # the block hash's path (docs/HASH.md)
    hash_path: str


def devices() -> List[Device]:
    """The Vulkan devices and whether vkmesh can use each (as `vkmesh devices` lists them)."""
    return [Device(**d) for d in _vkmesh._devices()]


def synth(out_dir, frames: int = 60, *, width: int = 640, height: int = 480, noise: bool = False, seed: int = 1,
          path: str = "orbit", color_noise: float = 0.0, exposure_drift: float = 0.0, gt_spacing: float = 0.005) -> str:
    """Renders the built-in synthetic room along a camera path into a TUM-layout folder with exact ground
    truth (depth/, rgb/, depth.txt, rgb.txt, groundtruth.txt, camera.json, gt_points.ply), as `vkmesh synth`
    does, with its defaults. Returns the folder, ready for open_dataset().

    noise           Kinect-like depth noise and dropout
    seed            noise seed
    path            'orbit' (one loop) or 'revisit' (the loop three times)
    color_noise     Gaussian colour noise per pixel and channel, sigma in 0-255 units
    exposure_drift  colour gain 1 + A sin(2 pi frame / frames) over the sequence, A in [0, 1)
    gt_spacing      metres between the ground-truth surface points of gt_points.ply, in [0.001, 1] (the default
                    writes ~2.4 million points, ~70 MB, for the room: a coarser spacing is much quicker where
                    they are not evaluated against)
    """
    # The ranges `vkmesh synth` accepts.
    if frames < 1:
        raise ValueError(f"frames {frames} must be >= 1")
    for name, value in (("width", width), ("height", height)):
        if not 16 <= value <= 4096:
            raise ValueError(f"{name} {value} must be in [16, 4096]")
    if path not in ("orbit", "revisit"):
        raise ValueError(f"path '{path}' is not one of 'orbit', 'revisit'")
    if not 0 <= color_noise <= 255:
        raise ValueError(f"color_noise {color_noise} must be in [0, 255]")
    if not 0 <= exposure_drift <= 0.999:
        raise ValueError(f"exposure_drift {exposure_drift} must be in [0, 0.999]")
    if not 0.001 <= gt_spacing <= 1:
        raise ValueError(f"gt_spacing {gt_spacing} must be in [0.001, 1]")
    if not 0 <= seed < 2**32:
        raise ValueError(f"seed {seed} must be in [0, 2^32)")
    out = os.fspath(out_dir)
    _vkmesh._synth(out, int(frames), int(width), int(height), bool(noise), int(seed), path, float(color_noise),
                   float(exposure_drift), float(gt_spacing))
    return out


def validation_messages() -> List[str]:
    """The Khronos validation layer's messages (with VKMESH_VALIDATION=1 or Reconstructor(validation=True))
    from every Reconstructor since the last call, which clears them. They are printed to stderr as well; the
    test suite fails on any."""
    return _vkmesh._take_validation_messages()
