#!/usr/bin/env bash
# Regenerates the measured tables of README.md (between the BEGIN/END markers) from runs:
#   - f32 accuracy of the recursive cores (host-tests/tests/recursive_f32.rs),
#   - `imu-ar compare` on a drifting AR(2),
#   - host cost per sample (criterion, host-tests/benches/per_sample.rs).
#
#   tools/readme-tables.sh            all of them (about 4 minutes)
#   tools/readme-tables.sh accuracy   one section: accuracy | compare | host-cost
set -euo pipefail
cd "$(dirname "$0")/.."
only=${1:-all}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# replace SECTION FILE: put FILE's contents between the section's markers in README.md.
replace() {
    python3 - "$1" "$2" <<'PY'
import re, sys
name, path = sys.argv[1], sys.argv[2]
body = open(path).read().rstrip("\n")
readme = open("README.md").read()
begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
if begin not in readme or end not in readme:
    sys.exit(f"README.md has no {begin} ... {end} section")
pre, rest = readme.split(begin, 1)
_, post = rest.split(end, 1)
open("README.md", "w").write(f"{pre}{begin}\n{body}\n{end}{post}")
PY
    echo "README.md: section $1 updated"
}

if [ "$only" = all ] || [ "$only" = accuracy ]; then
    cargo test --release -p imu-ar-host --test recursive_f32 -- --nocapture --test-threads 1 \
        > "$tmp/accuracy.txt" 2>/dev/null
    python3 - "$tmp" <<'PY'
import sys
tmp = sys.argv[1]
tables, current = {}, None
for line in open(f"{tmp}/accuracy.txt"):
    # libtest may print "test name ... " on the line where a table starts.
    if "| process |" in line:
        current, line = "f32-accuracy", line[line.index("| process |"):]
    elif "| record |" in line:
        current, line = "real-accuracy", line[line.index("| record |"):]
    elif not line.startswith("|"):
        current = None
    if current:
        tables.setdefault(current, []).append(line)
for name, lines in tables.items():
    open(f"{tmp}/{name}.md", "w").write("".join(lines))
PY
    replace f32-accuracy "$tmp/f32-accuracy.md"
    replace real-accuracy "$tmp/real-accuracy.md"
fi

if [ "$only" = all ] || [ "$only" = compare ]; then
    cargo build --release -q -p imu-ar-host
    tool=target/release/imu-ar
    "$tool" simulate --a 1.5,-0.7 --a-end 1.0,-0.7 --sigma 1 --n 100000 --seed 4 --rate 100 \
        > "$tmp/drift.csv"
    {
        echo "| lambda | batch LS MSE | RLS MSE | lattice MSE | lattice vs batch |"
        echo "|---|---|---|---|---|"
        for lambda in 0.99 0.999 0.9999; do
            "$tool" compare "$tmp/drift.csv" --column x --order 2 --lambda "$lambda" --json |
                python3 -c 'import json, sys
v = json.load(sys.stdin)
cells = [str(v["lambda"])] + ["%.4f" % v[k] for k in ("batch_mse", "rls_mse", "lattice_mse")]
print("| " + " | ".join(cells) + " | %.1f %% lower |" % v["reduction_percent"])'
        done
    } > "$tmp/compare.md"
    replace compare "$tmp/compare.md"
fi

if [ "$only" = all ] || [ "$only" = host-cost ]; then
    cargo bench -q -p imu-ar-host --bench per_sample > /dev/null
    python3 - > "$tmp/host-cost.md" <<'PY'
import json
orders = [2, 4, 8, 16, 32]
rows = [("lattice", "f32"), ("lattice", "f64"), ("rls", "f32"), ("rls", "f64")]
print("| estimator | scalar | " + " | ".join(f"p = {p}" for p in orders) + " |")
print("|---|---|" + "---|" * len(orders))
for est, scalar in rows:
    cells = []
    for p in orders:
        e = json.load(open(f"target/criterion/{est}_{scalar}/{p}/new/estimates.json"))
        cells.append(f"{e['mean']['point_estimate'] / 1000:.0f}")
    print(f"| {est} | {scalar} | " + " | ".join(cells) + " |")
PY
    replace host-cost "$tmp/host-cost.md"
fi
