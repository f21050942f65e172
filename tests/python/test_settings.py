"""Every setting is described once (src/api/settings.h): Python's keywords and their defaults, `vkmesh fuse`'s options
and the docs are checked against the descriptions here, so that none of them can drift from the others."""

import inspect
import math
import pathlib
import re

import numpy as np

import vkmesh
from conftest import run_cli

ROOT = pathlib.Path(__file__).resolve().parents[2]
SETTINGS = vkmesh._vkmesh._settings()
# Reconstructor keywords that are not settings of a run.
NOT_SETTINGS = set()


def reconstructor_keywords() -> dict:
    """Reconstructor(...)'s keyword arguments and their defaults, as pybind11 writes its signature."""
    doc = vkmesh.Reconstructor.__init__.__doc__
    signature = doc[doc.index("*, ") + 3:doc.index(") -> None")]
    out = {}
    for parameter in signature.split(", "):
        name, _, rest = parameter.partition(": ")
        _, _, default = rest.partition(" = ")
        out[name] = default
    return out


def same_default(python_default: str, described: str) -> bool:
    """A default as pybind11 prints it (0.03, True, 'average', None) against the description's text."""
    if described == "":
        return True   # no default worth stating (a path, a device chosen by the library)
    if python_default in ("True", "False"):
        return python_default.lower() == described
    if python_default.startswith("'"):
        return python_default.strip("'") == described
    try:
        return np.float32(float(python_default)) == np.float32(float(described))
    except ValueError:
        return False


def test_every_keyword_is_described_with_its_default():
    keywords = reconstructor_keywords()
    assert len(keywords) > 30, keywords
    described = {s["python"]: s for s in SETTINGS if s["python"]}
    assert sorted(set(keywords) - set(described) - NOT_SETTINGS) == []
    assert sorted(set(described) - set(keywords)) == []
    wrong = {k: (keywords[k], s["default"]) for k, s in described.items() if not same_default(keywords[k], s["default"])}
    assert wrong == {}


def test_merge_maps_keywords_are_the_settings_names():
    """vkmesh.merge_maps's keywords that are settings (`vkmesh merge --frames-budget`, ...) have the settings' Python names
    and defaults; keep_frames is True there, as --keep-frames is with --save (`vkmesh merge --no-frames` turns it off)."""
    parameters = inspect.signature(vkmesh.merge_maps).parameters
    described = {s["python"]: s for s in SETTINGS if s["python"]}
    own = {"inputs", "output", "mesh", "tiles", "tile_size", "register"}   # merge_maps's own arguments: the maps, where the mesh and tiles go, sessions
    assert sorted(set(parameters) - own - set(described)) == []
    assert {"keep_frames", "frames_budget_mb", "frames_spill", "device", "validation"} <= set(parameters)
    defaults = {name: p.default for name, p in parameters.items() if name not in own | {"keep_frames"}}
    wrong = {k: (v, described[k]["default"]) for k, v in defaults.items()
             if not same_default("''" if v is None else repr(v), described[k]["default"])}
    assert wrong == {}
    assert parameters["keep_frames"].default is True


def test_every_cli_setting_is_an_option_of_fuse_with_its_help():
    help_text = run_cli("fuse", "--help").stdout
    flat = " ".join(help_text.split())
    for s in SETTINGS:
        if not s["cli"]:
            continue
        assert s["cli"] in help_text, s["cli"]
        # CLI11 wraps nothing: the help is printed as described (whitespace aside).
        assert " ".join(s["help"].split()) in flat, s["cli"]


def test_ranges_and_choices_are_stated():
    kinds = {s["kind"] for s in SETTINGS}
    assert {"map", "capacity", "tracking", "correction", "instrumentation", "output"} <= kinds
    for s in SETTINGS:
        assert s["help"], s
        if s["choices"]:
            assert s["default"] in s["choices"] + ["auto"], s
        if s["default"] and not math.isinf(s["min"]) and not s["choices"]:
            v = float(s["default"])
            assert v > s["min"] if s["min_exclusive"] else v >= s["min"], s
            assert v <= s["max"], s
    # What --load takes from a map: the map settings, each with the copy it needs.
    assert {s["cli"] for s in SETTINGS if s["from_map"]} >= {"--voxel", "--trunc", "--min-weight", "--mode", "--refine", "--color-mode"}
    assert all(s["kind"] == "map" for s in SETTINGS if s["from_map"])


def test_the_docs_name_every_setting():
    docs = (ROOT / "README.md").read_text() + "".join(p.read_text() for p in (ROOT / "docs").glob("*.md"))
    python_docs = (ROOT / "docs" / "PYTHON.md").read_text()
    missing_cli = [s["cli"] for s in SETTINGS if s["cli"] and not re.search(re.escape(s["cli"]) + r"\b", docs)]
    missing_python = [s["python"] for s in SETTINGS if s["python"] and s["python"] not in python_docs]
    assert missing_cli == [] and missing_python == []
