#!/usr/bin/env bash
# The Python package, as a user installs it: a fresh virtual environment with the tests'
# dependencies, the abi3 wheel built by maturin (profile `wheel`) and installed into it, or with
# --source the package built from python/ by pip itself; then its tests (python/tests), which
# compare it with allantools, statsmodels and the tool (`cargo run -p imu-ar-cli`). Run by CI
# (.ci/run); never part of the README's test command, which runs with no Python.
#
#   tools/python-check.sh            # the wheel
#   tools/python-check.sh --source   # pip install ./python
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
venv=$(mktemp -d)
wheels=$(mktemp -d)
trap 'rm -rf "$venv" "$wheels"' EXIT
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet maturin numpy pytest allantools statsmodels matplotlib
if [ "${1:-}" = --source ]; then
    "$venv/bin/python" -m pip install --quiet ./python
else
    "$venv/bin/maturin" build --quiet --profile wheel -m python/Cargo.toml -o "$wheels"
    "$venv/bin/python" -m pip install --quiet "$wheels"/imu_ar-*.whl
fi
echo "python-check: installed in $(($(date +%s) - start)) s"
# From the repository's root: the source folder python/imu_ar (without its native module) is
# then not on the path, the installed package is.
MPLBACKEND=Agg "$venv/bin/pytest" -q -p no:cacheprovider python/tests
echo "python-check: done in $(($(date +%s) - start)) s"
