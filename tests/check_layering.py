#!/usr/bin/env python3
"""Every dependency points down (docs/ARCHITECTURE.md, "Layers"): checks the #include lines of src/, and that the
front ends that only feed the library's frame loop include no gpu/ header. Fails naming each include that breaks a
rule. Run by ctest (Layering.IncludesPointDown) and by hand: python3 tests/check_layering.py [REPO]."""
import pathlib
import re
import sys

# What each folder of src/ may include besides itself, lowest layer first. io/ holds two libraries: the readers and
# writers in vkmesh_base (BASE_IO, below) and the dataset I/O in vkmesh_io; the GPU core may include only the former.
ALLOWED = {
    "core": set(),
    "cpu": {"core"},
    "io": {"core"},
    "synth": {"core", "io"},
    "eval": {"core", "io"},
    "viewer": {"core", "io"},
    "vk": {"core"},
    "gpu": {"core", "vk", "io-base"},
    "render": {"core", "vk", "gpu", "io-base"},
    "api": {"core", "vk", "gpu", "render", "io-base"},
    "slam": {"core", "cpu", "vk", "gpu", "api"},
}
# The io/ headers compiled into vkmesh_base (CMakeLists.txt, VKMESH_BASE_SOURCES).
BASE_IO = {"io/ply.h", "io/delta_stream.h", "io/text_lines.h", "io/trajectory.h"}
# Front ends that drive the Mapper and must not reach past it into the GPU objects.
NO_GPU = ["host/fuse_command.cpp", "host/soak_command.cpp"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def includes(path):
    return INCLUDE.findall(path.read_text(encoding="utf-8", errors="replace"))


def check(repo):
    problems = []
    src = repo / "src"
    folders = {p.name for p in src.iterdir() if p.is_dir()}
    for folder in sorted(folders):
        if folder not in ALLOWED:
            problems.append(f"src/{folder}/ is not in tests/check_layering.py's ALLOWED: say which layers it may include")
            continue
        for path in sorted((src / folder).rglob("*")):
            if path.suffix not in (".h", ".cpp"):
                continue
            for inc in includes(path):
                top = inc.split("/")[0]
                if "/" not in inc or top not in folders or top == folder:
                    continue   # a system or shader header (shared_layout.h), or the folder's own
                allowed = ALLOWED[folder]
                if top in allowed or (top == "io" and "io-base" in allowed and inc in BASE_IO):
                    continue
                problems.append(f"{path.relative_to(repo)}: includes {inc}: src/{folder}/ may include only "
                                f"{', '.join(sorted(allowed)) or 'itself'}")
    for name in NO_GPU:
        path = repo / name
        for inc in includes(path):
            if inc.startswith("gpu/"):
                problems.append(f"{name}: includes {inc}: it drives the frame loop (api/mapper.h) and includes no gpu/ header")
    return problems


def main():
    repo = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[1])
    problems = check(repo)
    for p in problems:
        print(p)
    print(f"layering: {len(problems)} include(s) pointing the wrong way" if problems else "layering: every include points down")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
