#!/usr/bin/env bash
# `imu-ar characterise` beside what a notebook does first: a generated 1-hour, 400 Hz six-axis
# EuRoC CSV (1.44 M rows), characterised by the release build (Allan deviation, composite
# model, plots, seven parameter files), against pandas reading the same file and allantools
# computing the overlapping Allan deviation of its six columns at octave averaging times.
# Wall times of each, run one after the other on an otherwise idle machine, best of three;
# the table perf-versus-pandas of docs/recordings.md.
#
#   pip install pandas allantools
#   tools/csv-versus-pandas.sh [DIR]      (DIR: where the recording goes, default /tmp)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-/tmp}/imu-ar-versus

# replace SECTION FILE: put FILE's contents between the section's markers, in whichever of
# README.md and docs/*.md holds them.
replace() {
    python3 tools/readme.py replace "$1" "$2"
}
mkdir -p "$dir"
n=$((3600 * 400))
if [ ! -f "$dir/imu.csv" ]; then
    python3 tools/static-imu-csv.py "$dir/imu.csv" "$n" 11
fi
cargo build --release -p imu-ar-cli --quiet
best() {
    local best=
    for _ in 1 2 3; do
        local start end
        start=$(date +%s.%N)
        "$@" > /dev/null
        end=$(date +%s.%N)
        best=$(python3 -c "a, b = $end - $start, '${best}'; print(a if not b else min(a, float(b)))")
    done
    echo "$best"
}
tool=$(best target/release/imu-ar characterise "$dir/imu.csv" --out "$dir/out")
cat > "$dir/notebook.py" <<'PY'
import sys
import allantools
import numpy as np
import pandas as pd
frame = pd.read_csv(sys.argv[1])
rate = 400.0
taus = 2.0 ** np.arange(0, 21) / rate
for column in frame.columns[1:]:
    allantools.oadev(frame[column].to_numpy(), rate=rate, data_type="freq", taus=taus)
PY
notebook=$(best python3 "$dir/notebook.py" "$dir/imu.csv")
bytes=$(stat -c %s "$dir/imu.csv")
{
    echo "| the 1-hour, 400 Hz six-axis EuRoC CSV ($(((bytes + 500000) / 1000000)) MB) | wall (s) |"
    echo "|---|---|"
    printf '| pandas read_csv + allantools oadev of the six columns (octaves) | %.2f |\n' "$notebook"
    printf '| imu-ar characterise (Allan deviation, models, plots, seven files) | %.2f |\n' "$tool"
    python3 -c "print(f'| ratio | {$tool / $notebook:.2f} |')"
} > "$dir/table.md"
cat "$dir/table.md"
replace perf-versus-pandas "$dir/table.md"
