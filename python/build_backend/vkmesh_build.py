"""`pip install .` for vkmesh: a PEP 517 build backend, in the source tree, that drives the existing CMake build
of the Python module (python/CMakeLists.txt) and packs the result as a wheel. Standard library only.

Why not scikit-build-core (what issue 23 asked for): it is neither a Debian 12 package nor reachable here (no
PyPI on the developers' machines or in CI), and pip must fetch a build backend before it can build anything.
This backend needs nothing pip would have to download (build-system.requires = []), so `pip install .` works
offline in a fresh virtual environment. pyproject.toml keeps [tool.scikit-build] ready: where scikit-build-core
can be installed, switching is the two [build-system] lines there (docs/PYTHON.md, "pip install").

What it does (build_wheel):
  1. configures CMake in build/pip-<python tag> (kept between installs, so a second install is incremental),
     Release, tests off, the module built for the interpreter running pip (-DPython3_EXECUTABLE);
     `--config-settings=build-dir=DIR` reuses an existing configured build instead (CI: the test build's), which
     must be for the same Python version;
  2. builds the target vkmesh_python (CMAKE_BUILD_PARALLEL_LEVEL jobs, else all cores);
  3. writes the wheel: vkmesh/ (the compiled module and the pure-Python files as the build assembled them),
     vkmesh/data/ (camera presets, found through VKMESH_DATA_DIR, which vkmesh/__init__.py sets to it), and the
     dist-info (METADATA, WHEEL, RECORD).
The wheel is for this machine (a linux_x86_64-style platform tag, not manylinux): it links the system's Vulkan
and OpenCV libraries, which must be installed where it runs (scripts/install_deps.sh)."""
import base64
import hashlib
import os
import re
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]
NAME = "vkmesh"


def _version():
    text = (SOURCE / "CMakeLists.txt").read_text()
    return re.search(r"project\(vkmesh VERSION ([0-9.]+)", text).group(1)


def _tags():
    impl = f"cp{sys.version_info.major}{sys.version_info.minor}"
    abi = impl + ("d" if hasattr(sys, "gettotalrefcount") else "")
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return impl, abi, platform


def _metadata():
    readme = "vkmesh: real-time 3D reconstruction on any Vulkan device (TSDF fusion and incremental meshing)."
    return (f"Metadata-Version: 2.1\nName: {NAME}\nVersion: {_version()}\n"
            "Summary: Real-time TSDF fusion and incremental meshing on any Vulkan device\n"
            "Requires-Python: >=3.9\nRequires-Dist: numpy\n"
            f"Description-Content-Type: text/plain\n\n{readme}\n")


def _clean_env():
    # pip's isolated build environment hides the interpreter's site-packages (through PYTHONPATH and
    # PYTHONNOUSERSITE); CMake's FindPython must see numpy where the module will run, so those are dropped.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONNOUSERSITE", "PYTHONHOME")}
    return env


def _run(cmd, env):
    print("vkmesh build:", " ".join(map(str, cmd)), file=sys.stderr, flush=True)
    subprocess.run(list(map(str, cmd)), check=True, env=env, stdout=sys.stderr)


def _build(config_settings):
    settings = config_settings or {}
    env = _clean_env()
    impl, _, _ = _tags()
    given = settings.get("build-dir") or os.environ.get("VKMESH_PIP_BUILD_DIR")
    build = Path(given).resolve() if given else SOURCE / "build" / f"pip-{impl}"
    if given and not (build / "CMakeCache.txt").exists():
        raise RuntimeError(f"build-dir {build}: no CMakeCache.txt there (configure it first, or leave build-dir out)")
    if not given:
        _run(["cmake", "-S", SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DVKMESH_BUILD_TESTS=OFF",
              f"-DPython3_EXECUTABLE={sys.executable}"], env)
    cache = (build / "CMakeCache.txt").read_text()
    m = re.search(r"^Python3_EXECUTABLE:[A-Z]+=(.*)$", cache, re.M)
    built_for = m.group(1) if m else None
    if built_for:
        probe = subprocess.run([built_for, "-c", "import sys; print(sys.version_info[:2])"], capture_output=True, text=True, env=env)
        if probe.stdout.strip() != str(sys.version_info[:2]):
            raise RuntimeError(f"{build} builds the module for {built_for} (Python {probe.stdout.strip()}), "
                               f"but pip runs Python {sys.version_info[:2]}: leave build-dir out, or use a matching interpreter")
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
    _run(["cmake", "--build", build, "--target", "vkmesh_python", "-j", jobs], env)
    package = build / "python" / NAME
    if not any(package.glob("_vkmesh*.so")):
        raise RuntimeError(f"{package}: no compiled module after the build (was the Python module disabled? see the "
                           "CMake output: it needs python3-dev, pybind11-dev and numpy for this interpreter)")
    return package


def _record_line(arcname, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{arcname},sha256={digest},{len(data)}"


# ---- PEP 517 hooks ----

def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    info = Path(metadata_directory) / f"{NAME}-{_version()}.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(_metadata())
    return info.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    package = _build(config_settings)
    impl, abi, platform = _tags()
    version = _version()
    wheel_name = f"{NAME}-{version}-{impl}-{abi}-{platform}.whl"
    dist_info = f"{NAME}-{version}.dist-info"
    files = []
    for path in sorted(package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            files.append((f"{NAME}/{path.relative_to(package).as_posix()}", path.read_bytes()))
    for path in sorted((SOURCE / "data").rglob("*")):
        if path.is_file():
            files.append((f"{NAME}/data/{path.relative_to(SOURCE / 'data').as_posix()}", path.read_bytes()))
    files.append((f"{dist_info}/METADATA", _metadata().encode()))
    files.append((f"{dist_info}/WHEEL", (f"Wheel-Version: 1.0\nGenerator: vkmesh_build\nRoot-Is-Purelib: false\n"
                                         f"Tag: {impl}-{abi}-{platform}\n").encode()))
    record = [_record_line(name, data) for name, data in files] + [f"{dist_info}/RECORD,,"]
    out = Path(wheel_directory) / wheel_name
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files:
            z.writestr(name, data)
        z.writestr(f"{dist_info}/RECORD", "\n".join(record) + "\n")
    return wheel_name


def build_sdist(sdist_directory, config_settings=None):
    """The files git tracks (a fresh clone's content)."""
    listed = subprocess.run(["git", "-C", SOURCE, "ls-files", "-z"], capture_output=True, check=True).stdout.split(b"\0")
    base = f"{NAME}-{_version()}"
    name = f"{base}.tar.gz"
    with tarfile.open(Path(sdist_directory) / name, "w:gz") as tar:
        for rel in filter(None, listed):
            rel = rel.decode()
            if (SOURCE / rel).is_file():
                tar.add(SOURCE / rel, arcname=f"{base}/{rel}")
        info = tarfile.TarInfo(f"{base}/PKG-INFO")
        data = _metadata().encode()
        info.size = len(data)
        import io
        tar.addfile(info, io.BytesIO(data))
    return name
