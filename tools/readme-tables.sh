#!/usr/bin/env bash
# Regenerates the measured tables of README.md (between the BEGIN/END markers) from runs:
#   - f32 and fixed-point accuracy of the lattice (host-tests/tests/recursive_f32.rs, fixed.rs),
#   - the demo's output and footprint (`cargo qemu demo`, tools/footprint.sh),
#   - `imu-ar compare` on a drifting AR(2),
#   - the SFTF against the lattice and RLS: instructions per sample on the target (`cargo qemu
#     bench`) and restarts per 10^6 samples (host-tests/tests/sftf.rs).
#
# The performance tables are written by tools/bench-report.sh.
#
#   tools/readme-tables.sh            all of them (about 3 minutes)
#   tools/readme-tables.sh accuracy   one group: accuracy | demo | compare | sftf
#   tools/readme-tables.sh check-demo FILE   exit 1 when the README's demo-output block differs
#                                            from the demo output in FILE (CI)
set -euo pipefail
cd "$(dirname "$0")/.."
only=${1:-all}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# replace SECTION FILE: put FILE's contents between the section's markers in README.md.
replace() {
    python3 tools/readme.py replace "$1" "$2"
}

# tables OUTPUT HEADER=SECTION...: the markdown tables of a test's output, by header cell, into
# $tmp/SECTION.md (libtest may print "test name ... " on the line where a table starts).
tables() {
    python3 - "$tmp" "$@" <<'PY'
import sys
tmp, output, pairs = sys.argv[1], sys.argv[2], sys.argv[3:]
headers = dict(p.split("=", 1) for p in pairs)
tables, current = {}, None
for line in open(output):
    for header, name in headers.items():
        if header in line:
            current, line = name, line[line.index(header):]
            break
    else:
        if not line.startswith("|"):
            current = None
    if current:
        tables.setdefault(current, []).append(line)
for name in headers.values():
    open(f"{tmp}/{name}.md", "w").write("".join(tables[name]))
PY
}

# test_tables TEST HEADER=SECTION...: runs a host test in release and puts the tables it prints
# into their README sections.
test_tables() {
    local test=$1 pair
    shift
    cargo test --release -p imu-ar-host --test "$test" -- --nocapture --test-threads 1 \
        > "$tmp/$test.txt" 2>/dev/null
    tables "$tmp/$test.txt" "$@"
    for pair in "$@"; do
        replace "${pair#*=}" "$tmp/${pair#*=}.md"
    done
}

if [ "$only" = all ] || [ "$only" = accuracy ]; then
    test_tables recursive_f32 "| process |=f32-accuracy" "| record |=real-accuracy"
    test_tables fixed "| process |=fixed-accuracy" "| record |=fixed-real"
fi

# demo_block: the README's demo-output block from the demo's output on stdin.
demo_block() {
    echo '```text'
    grep -E 't=120\.0s|^INFO  check|demo:'
    echo '```'
}

if [ "$only" = check-demo ]; then
    # CI: fail when the block differs from what the demo prints (its output in file $2).
    demo_block < "${2:?usage: tools/readme-tables.sh check-demo DEMO_OUTPUT}" > "$tmp/demo-output.md"
    python3 tools/readme.py check demo-output "$tmp/demo-output.md"
    exit
fi

if [ "$only" = all ] || [ "$only" = demo ]; then
    cargo qemu demo 2>/dev/null | demo_block > "$tmp/demo-output.md"
    replace demo-output "$tmp/demo-output.md"
    tools/footprint.sh demo > "$tmp/footprint.md"
    replace footprint "$tmp/footprint.md"
fi

if [ "$only" = all ] || [ "$only" = compare ]; then
    cargo build --release -q -p imu-ar-cli
    tool=target/release/imu-ar
    "$tool" simulate --a 1.5,-0.7 --a-end 1.0,-0.7 --sigma 1 --n 100000 --seed 4 --rate 100 \
        > "$tmp/drift.csv"
    {
        echo "| lambda | batch LS MSE | RLS MSE | lattice MSE | SFTF MSE | SFTF rescues | lattice vs batch |"
        echo "|---|---|---|---|---|---|---|"
        for lambda in 0.99 0.999 0.9999; do
            "$tool" compare "$tmp/drift.csv" --column x --order 2 --lambda "$lambda" --json |
                python3 -c 'import json, sys
v = json.load(sys.stdin)
cells = [str(v["lambda"])] + ["%.4f" % v[k] for k in ("batch_mse", "rls_mse", "lattice_mse", "sftf_mse")]
cells.append(str(v["sftf_restarts"]))
print("| " + " | ".join(cells) + " | %.1f %% lower |" % v["reduction_percent"])'
        done
    } > "$tmp/compare.md"
    replace compare "$tmp/compare.md"
fi

if [ "$only" = all ] || [ "$only" = sftf ]; then
    cargo qemu bench 2>/dev/null > "$tmp/bench.txt"
    PYTHONPATH=tools python3 - "$tmp/bench.txt" > "$tmp/sftf-cost.md" <<'PY'
import sys
from readme import bench_rows
text = open(sys.argv[1]).read()
insns, size = bench_rows(text), bench_rows(text, "bytes")
orders = [4, 8, 16]
print("| estimator (f32) | " + " | ".join(f"p = {p}" for p in orders)
      + " | state bytes, " + ", ".join(f"p = {p}" for p in orders) + " |")
print("|---|" + "---|" * (len(orders) + 1))
for est in ("sftf", "lattice", "rls"):
    cells = [str(insns[(est, "f32")][p]) for p in orders]
    state = ", ".join(str(size[(est, "f32")][p]) for p in orders)
    print(f"| {est} | " + " | ".join(cells) + f" | {state} |")
PY
    replace sftf-cost "$tmp/sftf-cost.md"
    test_tables sftf "| process (10^6 samples) |=sftf-restarts" "| record (six axes=sftf-real"
fi
