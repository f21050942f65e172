"""Reconstructor.serve(): the live browser viewer from Python (docs/VIEWER.md). A raw WebSocket client
(tests/viewer/wsclient.py) plays the page: it must end with exactly the mesh that mesh() downloads."""
import socket
import sys
from pathlib import Path

import pytest

import vkmesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "viewer"))
import wsclient  # noqa: E402

if not hasattr(vkmesh.Reconstructor, "serve"):
    pytest.skip("the module has no serve()", allow_module_level=True)


def port_of(url):
    return int(url.rstrip("/").rsplit(":", 1)[1])


def test_page_follows_the_frames(small_sequence, capsys):
    frames = list(vkmesh.open_dataset(small_sequence))
    with vkmesh.Reconstructor(voxel_size=0.03, track_deltas=True) as r:
        url = r.serve(0)
        assert url.startswith("http://127.0.0.1:") and url in capsys.readouterr().out   # printed
        page = wsclient.Client(port_of(url))
        replica = wsclient.Replica()
        header = replica.apply(page.recv()[1])
        assert header["flags"] & 1 and header["source"] == 2 and len(replica.triangles) == 0   # live, empty so far
        for f in frames:
            r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
        while replica.frame < len(frames):
            header = replica.apply(page.recv()[1])
        assert header["flags"] & 2 and header["blocks"] > 0   # the camera and the counts come along
        mesh = r.mesh()
        assert len(replica.triangles) == len(mesh.triangles) > 0
        assert len(replica.vertices) == len(mesh.vertices)
        # A page that joins now gets the whole mesh in one message.
        late = wsclient.Replica()
        late.apply(wsclient.Client(port_of(url)).recv()[1])
        assert sorted(late.triangles.values()) == sorted(replica.triangles.values())
        done = r.stop_serving()
        assert done["pages"] == 2 and done["frames_published"] == len(frames)
        assert r.stop_serving() == {}


def test_serve_errors_name_the_problem(small_sequence):
    with vkmesh.Reconstructor(voxel_size=0.03) as r:
        with pytest.raises(vkmesh.Error, match="track_deltas=True"):
            r.serve(0)
    holder = socket.socket()
    holder.bind(("127.0.0.1", 0))
    holder.listen()
    port = holder.getsockname()[1]
    try:
        with vkmesh.Reconstructor(voxel_size=0.03, track_deltas=True) as r:
            with pytest.raises(vkmesh.Error, match=f"port {port} on 127.0.0.1 is in use"):
                r.serve(port)
            with pytest.raises(ValueError, match="70000"):
                r.serve(70000)
            f = next(iter(vkmesh.open_dataset(small_sequence)))
            r.integrate(f.depth, f.intrinsics, f.pose)
            with pytest.raises(vkmesh.Error, match="before the first integrate"):
                r.serve(0)
    finally:
        holder.close()
