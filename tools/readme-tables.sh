#!/usr/bin/env bash
# Regenerates the measured tables of README.md (between the BEGIN/END markers) from runs:
#   - f32 and fixed-point accuracy of the lattice (host-tests/tests/recursive_f32.rs, fixed.rs),
#   - the demo's output and footprint (`cargo qemu demo`, tools/footprint.sh),
#   - `imu-ar compare` on a drifting AR(2),
#   - `imu-ar noise` on every axis of both real records, the ADIS16405 gx composite next to the
#     two AR(1) hand-offs, its decomposition plot (docs/plots/adis-gx-noise.png) and the one of
#     the ax axis (docs/plots/adis-ax-noise.png),
#   - the SFTF against the lattice and RLS: instructions per sample on the target (`cargo qemu
#     bench`) and restarts per 10^6 samples (host-tests/tests/sftf.rs).
#
# The performance tables are written by tools/bench-report.sh.
#
#   tools/readme-tables.sh            all of them (about 3 minutes)
#   tools/readme-tables.sh accuracy   one group: accuracy | demo | compare | sftf | noise
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

if [ "$only" = all ] || [ "$only" = noise ]; then
    data=${IMU_AR_DATA:-../shared/data/imu}
    cargo build -q -p imu-ar-cli
    tool=target/debug/imu-ar
    adis="$data/adis16405_imu1_part1.csv $data/adis16405_imu1_part2.csv"
    mpu="$data/mpu6050_static_10min.csv"
    for axis in gx gy gz ax ay az; do
        # shellcheck disable=SC2086
        "$tool" noise $adis --column "$axis" --rate 100 --json > "$tmp/adis-$axis.json"
        "$tool" noise "$mpu" --column "$axis" --rate 100 --json > "$tmp/mpu-$axis.json"
    done
    for axis in ax ay az; do
        # shellcheck disable=SC2086
        "$tool" noise $adis --column "$axis" --rate 100 --oscillators --gm-states 5 --json \
            > "$tmp/adis-$axis-osc.json"
    done
    # shellcheck disable=SC2086
    "$tool" noise $adis --column gx --rate 100 --unit deg/s --plot docs/plots/adis-gx-noise.png > /dev/null
    # shellcheck disable=SC2086
    "$tool" noise $adis --column ax --rate 100 --unit g --plot docs/plots/adis-ax-noise.png > /dev/null
    # shellcheck disable=SC2086
    "$tool" kalman $adis --column gx --order 1 --rate 100 --filter-rate 100 --json > "$tmp/k1.json"
    # shellcheck disable=SC2086
    "$tool" kalman $adis --column gx --order 1 --rate 100 --decimate 1000 --filter-rate 100 \
        --json > "$tmp/k1000.json"
    python3 - "$tmp" <<'PY'
import json, math, sys
tmp = sys.argv[1]
load = lambda name: json.load(open(f"{tmp}/{name}.json"))
def at_1s(v):
    rows = v["allan"]
    i = next(k for k, r in enumerate(rows) if r["tau_s"] >= 1.0)
    (t0, d0), (t1, d1) = [(rows[k]["tau_s"], rows[k]["data_adev"]) for k in (i - 1, i)]
    w = math.log(1 / t0) / math.log(t1 / t0)
    return math.exp(math.log(d0) * (1 - w) + math.log(d1) * w)
def upto(v):
    last = v["allan"][-1]["tau_s"]
    e = v["explained_up_to_s"]
    return f"{e:g} s (every tau)" if e == last else f"{e:g} s of {last:g} s"
def sig(x):
    return "null" if x is None else f"{x:.4g}"
with open(f"{tmp}/noise-handoff.md", "w") as out:
    out.write("| model of ADIS16405 gx | filter states | N (deg/s/sqrt(Hz)) | B (deg/h) | K (deg/s/s/sqrt(Hz)) | Allan check holds up to |\n")
    out.write("|---|---|---|---|---|---|\n")
    for name, label in (("k1", "AR(1) of the 100 Hz samples"), ("k1000", "AR(1) of 10 s averages")):
        v = load(name)
        out.write(f"| {label} | 1 | – | – | – | {upto(v)} |\n")
    v = load("adis-gx")
    states = len(v["phi"])
    ar = v["ar"]["order"] if v["ar"] else 0
    out.write(f"| composite: white + AR({ar}) part + {len(v['gauss_markov'])} Gauss-Markov + random walk "
              f"| {states} | {sig(v['white_noise'])} | {sig(v['bias_instability']['value'] * 3600)} "
              f"| {sig(v['random_walk'])} | {upto(v)} |\n")
with open(f"{tmp}/noise-axes.md", "w") as out:
    out.write("| record | axis | AR order | Gauss-Markov terms | filter states | N | ADEV at 1 s | N / ADEV(1 s) | Allan check holds up to |\n")
    out.write("|---|---|---|---|---|---|---|---|---|\n")
    for rec, label in (("adis", "ADIS16405"), ("mpu", "MPU-6050")):
        for axis in ("gx", "gy", "gz", "ax", "ay", "az"):
            runs = [(axis, load(f"{rec}-{axis}"))]
            if rec == "adis" and axis.startswith("a"):
                runs.append((axis + " `--oscillators --gm-states 5`", load(f"{rec}-{axis}-osc")))
            for name, v in runs:
                ar = v["ar"]["order"] if v["ar"] else 0
                terms = len(v["gauss_markov"])
                osc = sum(1 for g in v["gauss_markov"] if "frequency_hz" in g)
                terms_text = f"{terms} ({osc} oscillator at {v['gauss_markov'][-1]['frequency_hz']:.2f} Hz)" if osc else str(terms)
                n, a1 = v["white_noise"], at_1s(v)
                out.write(f"| {label} | {name} | {ar} | {terms_text} | {len(v['phi'])} | {n:.4g} "
                          f"| {a1:.4g} | {n / a1:.3f} | {upto(v)} |\n")
PY
    replace noise-handoff "$tmp/noise-handoff.md"
    replace noise-axes "$tmp/noise-axes.md"
fi
