#!/usr/bin/env bash
# `imu-ar thermal` against the autopilots' numpy.polyfit fits on simulated warm-ups (uneven
# heating, 1 deg C temperature steps, a knock): prints a markdown table of what each
# correction leaves of the true bias. Builds nothing: the binary is $IMU_AR, or
# target/release/imu-ar. Needs python3 and numpy. See tools/thermal-versus-polyfit.py.
#
#   cargo build --release -p imu-ar-cli
#   tools/thermal-versus-polyfit.sh [--work DIR]
set -euo pipefail
here=$(dirname "$0")
bin=${IMU_AR:-$here/../target/release/imu-ar}
if [ ! -x "$bin" ]; then
    echo "thermal-versus-polyfit: no binary at $bin (build it, or set IMU_AR)" >&2
    exit 1
fi
exec python3 "$here/thermal-versus-polyfit.py" "$bin" "$@"
