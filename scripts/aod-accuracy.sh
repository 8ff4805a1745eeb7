#!/usr/bin/env bash
# AoD with calibrated transmit chains, from the command-line tools alone (issue 10's target:
# calibrated on one half of a drive among 4 APs, AoD on the other half).
#   scripts/aod-accuracy.sh BUILD_DIR WORK_DIR SEED...
# Per seed: an 80 s drive of share/scenarios/kidnapped.yaml, cut at t = 40 s; wifi-calibrate
# --transmit-chains on the first half with true poses (TUM) and with the drive's odometry;
# csi-bearings --algo aod --calib on the second half (every 2nd frame; STRIDE=N in the environment to change); AoD errors against
# the simulator's truth (frames.csv). Prints one line per seed and pose source, then the pooled
# figures. Needs ~2 GB of free space in WORK_DIR per seed while it runs.
set -euo pipefail
build=$(realpath "$1"); work=$2; shift 2
src=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work"; cd "$work"
plugin="$build/lib/libmrpt_wifi_obs.so"
# Resumable: steps whose outputs exist are skipped.
for seed in "$@"; do
    if [ ! -f aod$seed-odometry.csv ] && [ ! -f test$seed.rawlog ]; then
        nice "$build/bin/wifi-sim" "$src/share/scenarios/kidnapped.yaml" d$seed.rawlog \
            --truth-dir truth$seed --seed $seed --duration 80 -q
        nice rawlog-edit -p "$plugin" --cut -i d$seed.rawlog -o cal$seed.rawlog --to-time 1700000040 -w -q >/dev/null 2>&1
        nice rawlog-edit -p "$plugin" --cut -i d$seed.rawlog -o test$seed.rawlog --from-time 1700000040 -w -q >/dev/null 2>&1
        rm -f d$seed.rawlog
    fi
    for poses in truth odometry; do
        [ -f aod$seed-$poses.csv ] && continue
        if [ $poses = truth ]; then p=(--poses truth$seed/trajectory_tum.txt); else p=(--poses odometry --odom-origin 5.0 2.5 0); fi
        [ -d calib$seed-$poses ] || nice "$build/bin/wifi-calibrate" cal$seed.rawlog --array "$src/share/arrays/rt-ac86u.yaml" \
            --transmitters truth$seed/transmitters.yaml "${p[@]}" --transmit-chains --out calib$seed-$poses -q >/dev/null ||
            echo "seed $seed, $poses poses: wifi-calibrate left some transmitter uncalibrated (no AoD for it)" >&2
        nice "$build/bin/csi-bearings" test$seed.rawlog /dev/null --algo aod --calib calib$seed-$poses \
            --tx-array "$src/share/arrays/ap-linear-4.yaml" --csv aod$seed-$poses.csv.part -q --stride "${STRIDE:-2}" >/dev/null
        mv aod$seed-$poses.csv.part aod$seed-$poses.csv
    done
    rm -f cal$seed.rawlog test$seed.rawlog
done
python3 - "$@" <<'PY'
import csv, sys
def load(seed, poses):
    truth = {}
    for r in csv.DictReader(open(f"truth{seed}/frames.csv")):
        truth[(r["mac"], round(float(r["timestamp_unix"]), 4))] = float(r["aod_deg"])
    out = []
    for r in csv.DictReader(open(f"aod{seed}-{poses}.csv")):
        if r["has_aod"] != "1": continue
        t = truth.get((r["transmitter"], round(float(r["timestamp"]), 4)))
        if t is None: continue
        e = abs((float(r["aod_deg"]) - t + 180) % 360 - 180)
        out.append((e, float(r["aod_std_deg"])))
    return out
def line(name, v):
    e = sorted(x for x, _ in v); n = len(e)
    q = lambda p: e[min(n - 1, int(p * n))]
    print(f"{name}: {n} AoD, median {q(.5):.2f} deg, p90 {q(.9):.2f} deg, "
          f">30 deg {100*sum(x > 30 for x in e)/n:.1f} %, within 3 sigma "
          f"{100*sum(x <= 3*s for x, s in v)/n:.1f} %, within 2 sigma {100*sum(x <= 2*s for x, s in v)/n:.1f} %")
for poses in ("truth", "odometry"):
    pooled = []
    for seed in sys.argv[1:]:
        v = load(seed, poses); pooled += v; line(f"seed {seed} {poses} poses", v)
    line(f"all seeds, {poses} poses", pooled)
PY
