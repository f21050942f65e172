#!/usr/bin/env bash
# CI job: `pip install .` into a fresh virtual environment, then Python tests (tests/python) run from that
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
# The installed module is the main suite's build (build-dir=build), which the main suite tested whole: here the files
# that cover what installing can break (the package's Python layer, its data files, the examples, every setting and
# bad input, the CLI against the same run), two pytest runs side by side, one per core, each with its own
# temporary folder. The long runs of the same module (tracking, memory, correction, the viewer's server) are not
# repeated. Both must pass.
run_pytest() {
  VKMESH_VALIDATION=1 VKMESH_CLI="$PWD/build/vkmesh" PYTHONDONTWRITEBYTECODE=1 \
    "$venv/bin/python" -m pytest -q -p no:cacheprovider --basetemp="$venv/pytest-$1" "${@:2}"
}
run_pytest a tests/python/test_cli_equivalence.py tests/python/test_examples.py >"$venv/a.log" 2>&1 &
a_run=$!
status=0
run_pytest b tests/python/test_api.py tests/python/test_settings.py tests/python/test_bad_input.py || status=1
wait "$a_run" || status=1
cat "$venv/a.log"
exit "$status"
