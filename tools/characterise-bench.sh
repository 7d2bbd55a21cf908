#!/usr/bin/env bash
# The cost of `imu-ar characterise` on a long recording: a generated static IMU, six axes at
# 400 Hz for 4 hours (5.76 M messages), as a EuRoC CSV, a ROS 1 bag and a rosbag2 SQLite
# database (written by the Python package rosbags), each characterised by the release build;
# wall time and peak memory (maximum resident set) from GNU time, as the table
# perf-characterise of docs/recordings.md.
#
#   tools/characterise-bench.sh [DIR]      (DIR: where the recordings go, default /tmp)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-/tmp}/imu-ar-bench
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# replace SECTION FILE: put FILE's contents between the section's markers, in whichever of
# README.md and docs/*.md holds them.
replace() {
    python3 tools/readme.py replace "$1" "$2"
}
mkdir -p "$dir"
n=$((4 * 3600 * 400))
if [ ! -f "$dir/imu.csv" ]; then
    python3 - "$dir" "$n" <<'PY'
import sys
import numpy as np
out, n = sys.argv[1], int(sys.argv[2])
rng = np.random.default_rng(7)
dt = 1 / 400
t = 1_700_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 2_500_000 \
    + rng.integers(-20_000, 20_001, n)
white = np.array([1e-3, 1.2e-3, 0.8e-3, 2e-2, 2.5e-2, 3e-2]) / np.sqrt(dt)
walk = np.array([2e-5, 1e-5, 3e-5, 4e-4, 2e-4, 5e-4]) * np.sqrt(dt)
mean = np.array([0.01, -0.02, 0.005, 0.1, -0.2, 9.81])
x = mean + white * rng.standard_normal((n, 6)) + np.cumsum(walk * rng.standard_normal((n, 6)), 0)
with open(f"{out}/imu.csv", "w") as f:
    f.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
    step = 200_000
    for i in range(0, n, step):
        block = np.column_stack([t[i:i + step].astype(object), x[i:i + step]])
        f.write("\n".join(",".join([str(r[0])] + [repr(float(v)) for v in r[1:]]) for r in block))
        f.write("\n")
PY
fi
if [ ! -f "$dir/imu.bag" ]; then
    # The script's CSV header: t_ns,gx,gy,gz,ax,ay,az.
    sed '1s/.*/t_ns,gx,gy,gz,ax,ay,az/' "$dir/imu.csv" > "$dir/plain.csv"
    python3 cli/tests/fixtures/write_ros.py one "$dir/imu.bag" ros1 /imu0 lz4 "$dir/plain.csv"
    rm "$dir/plain.csv"
fi
if [ ! -f "$dir/imu.db3" ]; then
    sed '1s/.*/t_ns,gx,gy,gz,ax,ay,az/' "$dir/imu.csv" > "$dir/plain.csv"
    python3 cli/tests/fixtures/write_ros.py one "$dir/imu.db3" sqlite3 /imu0 none "$dir/plain.csv"
    rm "$dir/plain.csv"
fi
cargo build --release -p imu-ar-cli --quiet
{
    echo "| input | size | wall (s) | peak resident (MB) |"
    echo "|---|---|---|---|"
    for input in "EuRoC CSV=imu.csv" "ROS 1 bag, lz4 chunks=imu.bag --topic /imu0" \
        "ROS 2 database (.db3)=imu.db3 --topic /imu0"; do
        label=${input%%=*}
        # shellcheck disable=SC2086
        set -- ${input#*=}
        /usr/bin/time -o "$tmp/time.txt" -f "%e %M" \
            target/release/imu-ar characterise "$dir/$1" "${@:2}" --out "$dir/out" > "$dir/out.txt"
        head -n 1 "$dir/out.txt" >&2
        read -r wall kib < "$tmp/time.txt"
        bytes=$(stat -c %s "$dir/$1")
        # Sizes in MB of 10^6 bytes; GNU time's %M is in KiB.
        printf '| %s | %d MB | %.1f | %d |\n' "$label" $(((bytes + 500000) / 1000000)) "$wall" \
            $(((kib * 1024 + 500000) / 1000000))
    done
} > "$tmp/perf-characterise.md"
cat "$tmp/perf-characterise.md"
replace perf-characterise "$tmp/perf-characterise.md"
