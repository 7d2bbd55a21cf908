#!/usr/bin/env bash
# The cost of `imu-ar characterise` on a long recording: a generated static IMU, six axes at
# 400 Hz for 4 hours (5.76 M messages), as a EuRoC CSV, a ROS 1 bag and a rosbag2 SQLite
# database (written by the Python package rosbags), and a 1-hour, 1 kHz PX4 ULog file of the raw
# FIFO topics (tools/ulog-fifo.py), each characterised by the release build;
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
    python3 tools/static-imu-csv.py "$dir/imu.csv" "$n" 7
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
if [ ! -f "$dir/fifo.ulg" ]; then
    # A PX4 ULog file with the raw FIFO topics: 1 hour at 1 kHz.
    python3 tools/ulog-fifo.py "$dir/fifo.ulg" 3600 1000 7
fi
cargo build --release -p imu-ar-cli --quiet
{
    echo "| input | size | wall (s) | peak resident (MB) |"
    echo "|---|---|---|---|"
    for input in "EuRoC CSV=imu.csv" "ROS 1 bag, lz4 chunks=imu.bag --topic /imu0" \
        "ROS 2 database (.db3)=imu.db3 --topic /imu0" \
        "PX4 ULog, FIFO topics, 1 hour at 1 kHz=fifo.ulg"; do
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
