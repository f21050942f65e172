#!/usr/bin/env bash
# CI job: `pip install .` into a fresh virtual environment, then the Python test suite (tests/python) run from that
# environment against the installed package (not build/python). The venv sees Debian's numpy and pytest
# (--system-site-packages): pip cannot download anything here, and the package's one dependency is numpy.
# The build backend (python/build_backend/vkmesh_build.py, pyproject.toml) is told to reuse the main suite's
# Release build (`--config-settings=build-dir=build`), whose module is already built: the install then costs
# seconds instead of a second full build (~10 minutes on 2 cores; a plain `pip install .` in a fresh clone does
# that build, in build/pip-cp3XX: checked by hand, docs/PYTHON.md).
set -euo pipefail
cd "$(dirname "$0")/../.."
scripts/install_deps.sh
scripts/build.sh

venv="$(mktemp -d /tmp/vkmesh-venv.XXXXXX)"
trap 'rm -rf "$venv"' EXIT
/usr/bin/python3 -m venv --system-site-packages "$venv"
"$venv/bin/pip" install --no-input --disable-pip-version-check . --config-settings=build-dir=build
# Imported from the venv, with the data files the wheel carries.
(cd /tmp && "$venv/bin/python" -c "import vkmesh, os; assert vkmesh.__file__.startswith('$venv'), vkmesh.__file__; \
assert os.path.isfile(os.path.join(os.environ['VKMESH_DATA_DIR'], 'cameras', 'tum_fr1', 'camera.json'))")
# Two pytest runs side by side, one per core of the CI machine, each with its own temporary folder: test_tracking.py
# and test_memory.py (the two longest files), and the rest, about as long. Both must pass.
run_pytest() {
  VKMESH_VALIDATION=1 VKMESH_CLI="$PWD/build/vkmesh" PYTHONDONTWRITEBYTECODE=1 \
    "$venv/bin/python" -m pytest -q -p no:cacheprovider --basetemp="$venv/pytest-$1" "${@:2}"
}
long=(tests/python/test_tracking.py tests/python/test_memory.py)
run_pytest long "${long[@]}" >"$venv/long.log" 2>&1 &
long_run=$!
status=0
run_pytest rest tests/python "${long[@]/#/--ignore=}" || status=1
wait "$long_run" || status=1
cat "$venv/long.log"
exit "$status"
