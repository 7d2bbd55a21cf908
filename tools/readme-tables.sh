#!/usr/bin/env bash
# Regenerates the measured blocks (between the BEGIN/END markers) of README.md and of the
# guides under docs/ from runs:
#   - f32 and fixed-point accuracy of the lattice (host-tests/tests/host/recursive_f32.rs, fixed.rs),
#   - the demo's output and footprint (`cargo qemu demo`, tools/footprint.sh),
#   - `imu-ar compare` on a drifting AR(2),
#   - `imu-ar noise` on every axis of both real records, the ADIS16405 gx composite next to the
#     two AR(1) hand-offs, its decomposition plot (docs/plots/adis-gx-noise.png) and the one of
#     the ax axis (docs/plots/adis-ax-noise.png),
#   - the SFTF against the lattice and RLS: instructions per sample on the target (`cargo qemu
#     bench`) and restarts per 10^6 samples (host-tests/tests/host/sftf.rs),
#   - the README's headline figures (headline), from the blocks above and the performance
#     tables; last in `all`, and run by tools/bench-report.sh after the tables it reads.
#
# The performance tables are written by tools/bench-report.sh.
#
#   tools/readme-tables.sh            all of them (about 3 minutes)
#   tools/readme-tables.sh accuracy   one group: accuracy | demo | compare | sftf | noise | headline
#   tools/readme-tables.sh check-demo FILE   exit 1 when the README's demo-output block differs
#                                            from the demo output in FILE (CI)
#   README_CHECK=1 tools/readme-tables.sh GROUP   check the group's blocks instead of writing
#                                                 them (CI: headline)
set -euo pipefail
cd "$(dirname "$0")/.."
only=${1:-all}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# replace SECTION FILE: put FILE's contents between the section's markers, in whichever of
# README.md and docs/*.md holds them.
# With README_CHECK=1, check instead: exit 1 with a diff when the block differs (CI).
replace() {
    if [ -n "${README_CHECK:-}" ]; then
        python3 tools/readme.py check "$1" "$2"
    else
        python3 tools/readme.py replace "$1" "$2"
    fi
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

# test_tables TEST HEADER=SECTION...: runs a host test in release and writes the tables it
# prints into $tmp/SECTION.md, for `replace SECTION` (the section names stay literal, for
# `python3 tools/readme.py markers`).
test_tables() {
    local test=$1
    shift
    cargo test --release -p imu-ar-host --test host -- "$test::" --nocapture --test-threads 1 \
        > "$tmp/$test.txt" 2>/dev/null
    tables "$tmp/$test.txt" "$@"
}

if [ "$only" = all ] || [ "$only" = accuracy ]; then
    test_tables recursive_f32 "| process |=f32-accuracy" "| record |=real-accuracy"
    replace f32-accuracy "$tmp/f32-accuracy.md"
    replace real-accuracy "$tmp/real-accuracy.md"
    test_tables fixed "| process |=fixed-accuracy" "| record |=fixed-real"
    replace fixed-accuracy "$tmp/fixed-accuracy.md"
    replace fixed-real "$tmp/fixed-real.md"
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
    replace sftf-restarts "$tmp/sftf-restarts.md"
    replace sftf-real "$tmp/sftf-real.md"
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

if [ "$only" = all ] || [ "$only" = headline ]; then
    # The README's headline figures, each read from the block of a guide that measures it.
    PYTHONPATH=tools python3 - > "$tmp/headline.md" <<'PY'
import re
import textwrap
from readme import split

def rows(section, n=0):
    """The rows of the section's n-th markdown table, as {header: cell}."""
    tables, current = [], None
    for line in split(section)[1].splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if current is None:
                current = {"header": cells, "rows": []}
                tables.append(current)
            elif not set("".join(cells)) <= set("-:"):
                current["rows"].append(dict(zip(current["header"], cells)))
        else:
            current = None
    return tables[n]["rows"]

def row(section, estimator, scalar):
    return next(r for r in rows(section) if (r["estimator"], r["scalar"]) == (estimator, scalar))

def largest(cells):
    """The cell of the largest number (as written in the table)."""
    return max((c for c in cells if c), key=float)

p = "p = 4"
insns, fixed = row("perf-target", "lattice", "f32")[p], row("perf-target", "lattice", "fixed")[p]
state = row("perf-state", "lattice", "f32")[p]
f32 = largest([r["lattice f32"] for r in rows("f32-accuracy")]
              + [r["lattice f32, p = 1..8"] for r in rows("real-accuracy")])
fix = largest([r[k] for r in rows("fixed-accuracy") for k in r if k.startswith("p = ")]
              + [r["fixed, p = 1..8"] for r in rows("fixed-real")])
lower = sorted(float(r["lattice vs batch"].split()[0]) for r in rows("compare"))
gyros = [r for r in rows("noise-axes") if r["axis"] in ("gx", "gy", "gz")]
every = [r for r in gyros if "every tau" in r["Allan check holds up to"]]
def item(text):
    """A list item wrapped at 100 columns, never inside a bold figure or a link's text."""
    keep = lambda m: m.group(0).replace(" ", "\xa0")
    text = re.sub(r"\*\*[^*]+\*\*|\[[^]]+\]", keep, text)
    print(textwrap.fill(text, 100, subsequent_indent="  ", break_long_words=False,
                        break_on_hyphens=False).replace("\xa0", " "))

item(f"- An order-4 `f32` lattice costs **{insns}** instructions per sample on the Cortex-M4F "
      f"and keeps **{state}** bytes of state per axis; the fixed-point lattice, **{fixed}** "
      "instructions ([Performance](docs/performance.md)).")
item(f"- The `f32` lattice's coefficients stay within **{f32}** of an `f64` direct solve of the "
      "same problem, on simulated processes and on every axis of two real records; the "
      f"fixed-point lattice's within **{fix}** ([Online estimation](docs/estimators.md#accuracy-in-f32)).")
item(f"- On an AR(2) whose dynamics drift, the lattice's mean squared one-step prediction error is "
      f"**{lower[0]:.1f} %** to **{lower[-1]:.1f} %** below that of a batch fit "
      "([Batch against recursive](docs/estimators.md#batch-against-recursive-one-step-prediction-error)).")
item(f"- The composite noise model explains the Allan deviation of **{len(every)} of {len(gyros)}** "
      "gyro axes of the two real records at every averaging time "
      "([Noise model](docs/noise-model.md#the-composite-noise-model)).")
versus = {r[next(iter(r))]: r["wall (s)"] for r in rows("perf-versus-pandas")}
tool = next(v for k, v in versus.items() if k.startswith("imu-ar characterise"))
notebook = next(v for k, v in versus.items() if k.startswith("pandas"))
item(f"- `imu-ar characterise` of a 1-hour, 400 Hz six-axis EuRoC CSV (Allan deviation, models, "
      f"plots and seven parameter files) takes **{tool} s**, **{versus['ratio']}** times the "
      f"**{notebook} s** that pandas and allantools take to read the file and compute its Allan "
      "deviations (`tools/csv-versus-pandas.sh`, [Recordings](docs/recordings.md)).")
PY
    replace headline "$tmp/headline.md"
fi
