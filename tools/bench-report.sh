#!/usr/bin/env bash
# Regenerates the guide docs/performance.md (between the BEGIN/END perf-* markers) from these
# runs, about 6 minutes:
#   - instructions per sample and state bytes per channel on the emulated Cortex-M4F
#     (`cargo qemu bench`), with the per-stage slope and the order where the lattice overtakes
#     RLS,
#   - nanoseconds per sample on the host (criterion, bench/benches/per_sample.rs),
#   - flash per estimator: each `size_*` firmware minus `size_base` (tools/footprint.sh),
#   - wall time of the `imu-ar` tool on the 1,000,000-row ADIS16405 record (best of 3),
#   - the same bench built for ARMv7-M without an FPU (thumbv7m-none-eabi, soft-float f32),
#     run on the same emulated core,
#   - the same bench built for ARMv6-M (thumbv6m-none-eabi, the Cortex-M0+), run on the same
#     emulated core, with the state bytes and the flash of the lattices built for it,
#   - after target, nofpu and v6m: the sentence of the lattice's per-stage cost on each core
#     (perf-stage), from the figures in those sections of docs/performance.md,
#   - after target: the README's headline figures (`tools/readme-tables.sh headline`), which
#     read the perf-target and perf-state tables.
#
#   tools/bench-report.sh            all of it
#   tools/bench-report.sh target     one part: target | host | flash | wall | nofpu | v6m
set -euo pipefail
cd "$(dirname "$0")/.."
only=${1:-all}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
data=${IMU_AR_DATA:-../shared/data/imu}

# replace SECTION FILE: put FILE's contents between the section's markers, in whichever of
# README.md and docs/*.md holds them.
replace() {
    python3 tools/readme.py replace "$1" "$2"
}

# stage: the per-stage cost of the f32 and fixed-point lattice on each core, from the "Per
# lattice stage" lines of the perf-target, perf-nofpu and perf-v6m sections (a core whose
# section has none is left out).
stage() {
    PYTHONPATH=tools python3 - > "$tmp/perf-stage.md" <<'PY'
import re
from readme import split
cores = [("perf-target", "Cortex-M4F"), ("perf-nofpu", "ARMv7-M without an FPU"),
         ("perf-v6m", "ARMv6-M")]
found = []
for section, core in cores:
    m = re.search(r"Per lattice stage.*?\*\*([\d.]+)\*\* instructions in (?:soft-float )?f32, "
                  r"\*\*([\d.]+)\*\* in fixed point", split(section)[1])
    if m:
        found.append(f"{core} **{m.group(1)}** / **{m.group(2)}**")
print("The lattice grows linearly in `p`, RLS quadratically. One lattice stage, in instructions, "
      f"f32 / fixed point: {', '.join(found)} (least-squares slopes over p = 1..32; f32 in "
      "software on the cores without an FPU).")
PY
    replace perf-stage "$tmp/perf-stage.md"
}

if [ "$only" = all ] || [ "$only" = target ]; then
    cargo qemu bench 2>/dev/null > "$tmp/bench.txt"
    PYTHONPATH=tools python3 - "$tmp/bench.txt" "$tmp" <<'PY'
import sys
from readme import bench_rows, slope, table
text, tmp = open(sys.argv[1]).read(), sys.argv[2]
insns, size = bench_rows(text), bench_rows(text, "bytes")
lat, fix, rls = insns[("lattice", "f32")], insns[("lattice", "fixed")], insns[("rls", "f32")]
s_f32, s_fixed = slope(lat), slope(fix)
common = sorted(set(lat) & set(rls))
cheaper = [p for p in common if all(lat[q] < rls[q] for q in common if q >= p)]
cross = cheaper[0] if cheaper else None
below = max((p for p in common if cross and p < cross), default=None)
with open(f"{tmp}/perf-target.md", "w") as out:
    out.write(table(insns))
    out.write(f"\nPer lattice stage (least-squares slope over p = 1..32): **{s_f32:.1f}** instructions "
              f"in f32, **{s_fixed:.0f}** in fixed point ({s_fixed / s_f32:.1f} times the f32 figure).")
    if cross:
        out.write(f" The f32 lattice is cheaper than RLS from **p = {cross}** on "
                  f"(p = {below}: lattice {lat[below]}, RLS {rls[below]}; p = {cross}: lattice "
                  f"{lat[cross]}, RLS {rls[cross]}).\n")
    else:
        out.write(" RLS is cheaper at every measured order.\n")
with open(f"{tmp}/perf-state.md", "w") as out:
    out.write(table(size))
PY
    replace perf-target "$tmp/perf-target.md"
    replace perf-state "$tmp/perf-state.md"
    python3 - "$tmp/bench.txt" > "$tmp/perf-noise.md" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
print("| noise-model fit, 20 octaves, budget 3 | instructions | stack (bytes) | Gauss-Markov terms |")
print("|---|---|---|---|")
for ar, insns, stack, terms in re.findall(r"noise fit octaves=20 gm=3 ar=(\w+) insns/fit=(\d+) stack=(\d+) terms=(\d+)", text):
    label = "with an AR(8) part" if ar.startswith("ar8") else "without an AR part"
    if ar.endswith("_identified"):
        label += ", identified, with the 95 % intervals"
    print(f"| {label} | {int(insns):,} | {int(stack):,} | {terms} |")
m = re.search(r"allan_stream_l20 bytes=(\d+) noise_model_p8_g3 bytes=(\d+) octaves_l20 bytes=(\d+)", text)
print()
print(f"State: `AllanStream<20>` {m.group(1)} bytes (kept per axis, fed every sample), "
      f"`Octaves<20>` {m.group(3)} bytes, `NoiseModel<8, 3>` {m.group(2)} bytes.")
PY
    replace perf-noise "$tmp/perf-noise.md"
    stage
    tools/readme-tables.sh headline
fi

if [ "$only" = all ] || [ "$only" = host ]; then
    cargo bench -q -p imu-ar-bench --bench per_sample > /dev/null
    python3 - > "$tmp/perf-host.md" <<'PY'
import json, os
orders = [1, 2, 4, 8, 16, 32]
rows = [("lattice", "f32"), ("lattice", "f64"), ("lattice", "fixed"), ("rls", "f32"),
        ("rls", "f64"), ("sftf", "f32"), ("sftf", "f64"), ("extract", "f32"), ("frame6", "f32")]
print("| estimator | scalar | " + " | ".join(f"p = {p}" for p in orders) + " |")
print("|---|---|" + "---|" * len(orders))
for est, scalar in rows:
    cells = []
    for p in orders:
        path = f"target/criterion/{est}_{scalar}/{p}/new/estimates.json"
        if not os.path.exists(path):
            cells.append("")
            continue
        ns = json.load(open(path))["mean"]["point_estimate"]
        # A block of 1000 samples (frames) per iteration; extract times one request.
        per = ns if est == "extract" else ns / 1000
        cells.append(f"{per:.0f}" if per >= 10 else f"{per:.1f}")
    print(f"| {est} | {scalar} | " + " | ".join(cells) + " |")
PY
    replace perf-host "$tmp/perf-host.md"
fi

if [ "$only" = all ] || [ "$only" = flash ]; then
    tools/footprint.sh size_base size_lattice_f32 size_lattice_fixed size_rls_f32 > "$tmp/sizes.md"
    python3 - "$tmp/sizes.md" > "$tmp/perf-flash.md" <<'PY'
import re, sys
flash = dict(re.findall(r"\| `(\w+)` \| (\d+) \|", open(sys.argv[1]).read()))
base = int(flash.pop("size_base"))
names = {"size_lattice_f32": ("lattice", "f32"), "size_lattice_fixed": ("lattice", "fixed"),
         "size_rls_f32": ("rls", "f32")}
print("| estimator | scalar | flash (bytes), p = 8 | firmware |")
print("|---|---|---|---|")
for name, total in flash.items():
    est, scalar = names[name]
    print(f"| {est} | {scalar} | {int(total) - base} | `{name}`: {total} - `size_base`: {base} |")
PY
    replace perf-flash "$tmp/perf-flash.md"
fi

if [ "$only" = all ] || [ "$only" = wall ]; then
    cargo build --release -q -p imu-ar-cli
    python3 - "$data" > "$tmp/perf-wall.md" <<'PY'
import subprocess, sys, time
data = sys.argv[1]
files = [f"{data}/adis16405_imu1_part1.csv", f"{data}/adis16405_imu1_part2.csv"]
runs = [
    ("fit --method lattice --order 4", ["fit", "--method", "lattice", "--order", "4"]),
    ("fit --method lattice --order 32", ["fit", "--method", "lattice", "--order", "32"]),
    ("fit --method lattice --order 4 --scalar fixed",
     ["fit", "--method", "lattice", "--order", "4", "--scalar", "fixed"]),
    ("fit --method yule-walker --order 1", ["fit", "--method", "yule-walker", "--order", "1"]),
    ("adev --rate 100", ["adev", "--rate", "100"]),
]
print("| `imu-ar ... --column gx` on both ADIS16405 files (1,000,000 rows) | wall (s) |")
print("|---|---|")
for label, args in runs:
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run(["target/release/imu-ar", *args, "--column", "gx", *files],
                       check=True, stdout=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - start)
    print(f"| `{label}` | {best:.2f} |")
PY
    replace perf-wall "$tmp/perf-wall.md"
fi

if [ "$only" = all ] || [ "$only" = nofpu ]; then
    rustup target list --installed | grep -qx thumbv7m-none-eabi ||
        rustup target add thumbv7m-none-eabi
    cargo run -q --release --target thumbv7m-none-eabi --example bench 2>/dev/null \
        > "$tmp/nofpu.txt"
    PYTHONPATH=tools python3 - "$tmp/nofpu.txt" > "$tmp/perf-nofpu.md" <<'PY'
import sys
from readme import bench_rows, slope, table
rows = {k: r for k, r in bench_rows(open(sys.argv[1]).read()).items() if k[0] in ("lattice", "rls")}
print(table(rows), end="")
f32, fixed = slope(rows[("lattice", "f32")]), slope(rows[("lattice", "fixed")])
print(f"\nPer lattice stage: **{f32:.0f}** instructions in soft-float f32, **{fixed:.0f}** in fixed "
      f"point ({f32 / fixed:.1f} times cheaper).")
PY
    replace perf-nofpu "$tmp/perf-nofpu.md"
    stage
fi

if [ "$only" = all ] || [ "$only" = v6m ]; then
    rustup target list --installed | grep -qx thumbv6m-none-eabi ||
        rustup target add thumbv6m-none-eabi
    cargo run -q --release --target thumbv6m-none-eabi --example bench 2>/dev/null \
        > "$tmp/v6m.txt"
    tools/footprint.sh --target thumbv6m-none-eabi \
        size_base size_lattice_f32 size_lattice_fixed > "$tmp/v6m-sizes.md"
    PYTHONPATH=tools python3 - "$tmp/v6m.txt" "$tmp/v6m-sizes.md" > "$tmp/perf-v6m.md" <<'PY'
import re, sys
from readme import bench_rows, slope, split, table
text = open(sys.argv[1]).read()
rows = {k: r for k, r in bench_rows(text).items() if k[0] in ("lattice", "rls")}
print(table(rows), end="")
f32, fixed = slope(rows[("lattice", "f32")]), slope(rows[("lattice", "fixed")])
print(f"\nPer lattice stage: **{f32:.0f}** instructions in soft-float f32, **{fixed:.0f}** in fixed "
      f"point ({f32 / fixed:.1f} times cheaper).")
state = table({k: r for k, r in bench_rows(text, "bytes").items() if k[0] == "lattice"})
# The same rows in the Cortex-M4F's state table (perf-state)?
same = all(line in split("perf-state")[1].splitlines() for line in state.splitlines()[2:])
print(f"\nState per channel (bytes{', as on the Cortex-M4F' if same else ''}):\n")
print(state, end="")
flash = {k: int(v) for k, v in re.findall(r"\| `(\w+)` \| (\d+) \|", open(sys.argv[2]).read())}
base = flash["size_base"]
print(f"\nFlash at p = 8 (`update` and `model`, each `size_*` firmware minus `size_base`, "
      f"{base} bytes): lattice f32 **{flash['size_lattice_f32'] - base}** bytes, "
      f"lattice fixed **{flash['size_lattice_fixed'] - base}**.")
PY
    replace perf-v6m "$tmp/perf-v6m.md"
    stage
fi
