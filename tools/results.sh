#!/usr/bin/env bash
# Regenerates the tables of docs/results.md and docs/noise-model.md from the `imu-ar` tool's
# JSON, and the plots docs/results.md shows (docs/plots), in about 4 minutes:
#   - results-sim: a stationary AR(4) with known coefficients, every estimator against truth,
#   - results-real: batch LS against RLS and the lattice, one-step prediction MSE, on every
#     gyro axis of the ADIS16405 and MPU-6050 records at about 100 Hz and decimated to 10 Hz
#     and 1 Hz (batch model fitted on the first half, all evaluated on the second),
#   - handoff: the Kalman hand-off of the ADIS16405 gx axis (`imu-ar kalman`, in
#     docs/noise-model.md),
#   - docs/plots: `imu-ar report` on the drifting AR(2) (with the lattice from its correct
#     prior) and on gx of both records.
#
#   tools/results.sh
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
data=${IMU_AR_DATA:-../shared/data/imu}
# IMU_AR_TOOL: an `imu-ar` already built (the same numbers in any profile).
tool=${IMU_AR_TOOL:-}
if [ -z "$tool" ]; then
    cargo build --release -q -p imu-ar-cli
    tool=target/release/imu-ar
fi

# replace SECTION FILE: put FILE's contents between the section's markers, in whichever of
# README.md and docs/*.md holds them.
replace() {
    python3 tools/readme.py replace "$1" "$2"
}

# Simulated: the Percival-Walden AR(4) is hard (poles near the unit circle); a milder AR(4) too.
{
    echo "| process | n | method | max abs coefficient error |"
    echo "|---|---|---|---|"
    for spec in "2.7607,-3.8106,2.6535,-0.9238:Percival-Walden AR(4)" \
                "0.9,-0.3,0.1,-0.05:AR(4) 0.9, -0.3, 0.1, -0.05"; do
        a=${spec%%:*}
        name=${spec#*:}
        for n in 1000 100000; do
            "$tool" simulate --a "$a" --sigma 1 --n "$n" --seed 11 > "$tmp/sim.csv"
            for method in ls burg yule-walker rls lattice "rls settled" "lattice settled"; do
                extra=()
                case $method in
                    rls|lattice) extra=(--lambda 1);;
                    *settled) extra=(--lambda 1 --settle 500);;
                esac
                "$tool" fit "$tmp/sim.csv" --column x --method "${method%% *}" --order 4 \
                    "${extra[@]}" --json | python3 -c 'import json, sys
v = json.load(sys.stdin)
truth = [float(t) for t in sys.argv[1].split(",")]
err = max(abs(a - t) for a, t in zip(v["a"], truth))
print("| %s | %d | %s | %.2g |" % (sys.argv[2], v["n"], sys.argv[3], err))' "$a" "$name" "$method"
            done
        done
    done
} > "$tmp/results-sim.md"
replace results-sim "$tmp/results-sim.md"

adis=("$data/adis16405_imu1_part1.csv" "$data/adis16405_imu1_part2.csv")
mpu=("$data/mpu6050_static_10min.csv")
{
    echo "| record | axis | rate | lambda | n eval | batch LS MSE | RLS MSE | lattice MSE | lattice vs batch |"
    echo "|---|---|---|---|---|---|---|---|---|"
    for record in ADIS16405 MPU-6050; do
        if [ "$record" = ADIS16405 ]; then files=("${adis[@]}"); else files=("${mpu[@]}"); fi
        for axis in gx gy gz; do
            for decimate in 1 10 100; do
                "$tool" compare "${files[@]}" --column "$axis" --order 4 --lambda 0.999 \
                    --decimate "$decimate" --json | python3 -c 'import json, sys
v = json.load(sys.stdin)
rate = {1: "100 Hz", 10: "10 Hz", 100: "1 Hz"}[v["decimate"]]
cells = [sys.argv[1], sys.argv[2], rate, str(v["lambda"]), str(v["n_eval"])]
cells += ["%.3g" % v[k] for k in ("batch_mse", "rls_mse", "lattice_mse")]
print("| " + " | ".join(cells) + " | %+.1f %% |" % -v["reduction_percent"])' "$record" "$axis"
            done
        done
    done
} > "$tmp/results-real.md"
replace results-real "$tmp/results-real.md"

# The Kalman hand-off of the ADIS16405 gx axis: an AR(1) at the full rate and an AR(1) of
# 10-s averages (a Gauss-Markov drift), both at a 100 Hz filter, with their Allan checks.
for dec in 1 1000; do
    "$tool" kalman "${adis[@]}" --column gx --order 1 --rate 100 --decimate "$dec" \
        --filter-rate 100 --json > "$tmp/kalman-$dec.json"
done
python3 - "$tmp/kalman-1.json" "$tmp/kalman-1000.json" > "$tmp/handoff.md" <<'PY'
import json, sys
fits = [json.load(open(f)) for f in sys.argv[1:]]
names = ["100 Hz samples", "10 s averages"]
print("| AR(1) fitted on | a_1 | sigma_w^2 ((deg/s)^2) | T_c (s) | sigma (deg/s) "
      "| Phi at 100 Hz | Q at 100 Hz ((deg/s)^2) | Allan check holds up to |")
print("|---|---|---|---|---|---|---|---|")
for name, v in zip(names, fits):
    gm = v["gauss_markov"]
    print("| %s | %.4g | %.4g | %.4g | %.4g | %.6g | %.4g | %s s |" % (
        name, v["a"][0], v["noise_variance"], gm["correlation_time_s"], gm["sigma"],
        v["phi"][0][0], v["q"][0][0], "%.4g" % v["explained_up_to_s"]))
print()
print("| tau (s) | data ADEV (deg/s) | model ADEV (deg/s) | data / model | tolerance | fitted on |")
print("|---|---|---|---|---|---|")
for name, v in zip(names, fits):
    for row in v["allan"]:
        if row["tau_s"] < 5:
            continue
        print("| %.4g | %.3g | %.3g | %.2f | %.2f | %s |" % (
            row["tau_s"], row["data_adev"], row["model_adev"], row["data_over_model"],
            row["tolerance"], name))
PY
replace handoff "$tmp/handoff.md"

# The plots docs/results.md shows: the drifting AR(2), and gx of each real record at its full
# rate.
plots=docs/plots
mkdir -p "$plots"
"$tool" simulate --a 1.5,-0.7 --a-end 1.0,-0.7 --sigma 1 --n 100000 --seed 4 > "$tmp/drift.csv"
"$tool" report "$tmp/drift.csv" --column x --order 2 --lambda 0.999 --rate 1 \
    --prior-a 1.5,-0.7 --prior-weight 300 --out "$tmp/drift" > /dev/null
"$tool" report "${adis[@]}" --column gx --order 4 --lambda 0.999 --rate 100 --unit deg/s \
    --reference "$data/adis16405_imu1_allan_reference.csv" --out "$tmp/adis" > /dev/null
"$tool" report "${mpu[@]}" --column gx --order 4 --lambda 0.999 --rate 99.3 --unit deg/s \
    --out "$tmp/mpu" > /dev/null
cp "$tmp/drift/coefficients.png" "$plots/drift-coefficients.png"
cp "$tmp/drift/prediction_error.png" "$plots/drift-prediction-error.png"
cp "$tmp/drift/prior.png" "$plots/drift-prior.png"
for record in adis mpu; do
    cp "$tmp/$record/psd.png" "$plots/$record-gx-psd.png"
    cp "$tmp/$record/adev.png" "$plots/$record-gx-adev.png"
done
ls -l "$plots"
