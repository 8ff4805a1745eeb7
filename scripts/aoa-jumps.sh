#!/usr/bin/env bash
# Receiver AoA through the RT-AC86U's receive-chain jump states (issue 21), from the command-line
# tools alone, on share/scenarios/loop.yaml as shipped (3 states, 3 ns apart, 0.05 Hz) and on
# the same drive with the jumps off.
#   scripts/aoa-jumps.sh BUILD_DIR WORK_DIR SEED...
# Per seed and case (jumps, nojumps): a 120 s drive (wifi-sim -s SEED -d 120); receiver
# offsets (1) true, with every jump state (bearing-accuracy --truth-calibration) and (2) from
# wifi-calibrate on the drive's first 60 s with true poses (--force: loop.yaml's hall is larger
# than the calibration's 8 m distance advice, so it warns); csi-bearings (default estimator) on
# the last 60 s; AoA errors against the simulator's truth (frames.csv; the linear array's
# mirror folded). Prints one line per seed, case and calibration, then the pooled figures.
# RATE_HZ=X in the environment switches the jumps at X Hz instead (with a constant phase per
# state, state_phase: true).
set -euo pipefail
build=$(realpath "$1"); work=$2; shift 2
src=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work/scenarios"; cd "$work"
ln -sfn "$src/share/arrays" arrays
plugin="$build/lib/libmrpt_wifi_obs.so"
shipped='antenna_jumps: {enabled: true, states: 3, step_ns: 3, rate_hz: 0.05}'
grep -qF "$shipped" "$src/share/scenarios/loop.yaml" || { echo "loop.yaml's antenna_jumps changed" >&2; exit 1; }
if [ -n "${RATE_HZ:-}" ]; then
  sed "s|$shipped|antenna_jumps: {enabled: true, states: 3, step_ns: 3, rate_hz: $RATE_HZ, state_phase: true}|" \
    "$src/share/scenarios/loop.yaml" > scenarios/jumps.yaml
else
  cp "$src/share/scenarios/loop.yaml" scenarios/jumps.yaml
fi
sed "s|$shipped|antenna_jumps: {enabled: false}|" "$src/share/scenarios/loop.yaml" > scenarios/nojumps.yaml
for seed in "$@"; do
  for case in jumps nojumps; do
    tag=$case$seed
    [ -f aoa-$tag-drive.csv ] && continue
    nice "$build/bin/wifi-sim" scenarios/$case.yaml d$tag.rawlog -t truth$tag -s $seed -d 120 -q
    nice "$build/bin/bearing-accuracy" --truth-calibration scenarios/$case.yaml calib-$tag-truth --seed $seed >/dev/null
    t0=$(awk -F, 'NR==2{printf "%d", $1}' truth$tag/frames.csv)
    nice rawlog-edit -p "$plugin" --cut -i d$tag.rawlog -o cal$tag.rawlog --to-time $((t0 + 60)) -w -q >/dev/null 2>&1
    nice rawlog-edit -p "$plugin" --cut -i d$tag.rawlog -o test$tag.rawlog --from-time $((t0 + 60)) -w -q >/dev/null 2>&1
    rm -f d$tag.rawlog
    nice "$build/bin/wifi-calibrate" cal$tag.rawlog --array "$src/share/arrays/rt-ac86u.yaml" \
      --transmitters truth$tag/transmitters.yaml --poses truth$tag/trajectory_tum.txt \
      --out calib-$tag-drive --force -q > calibrate-$tag.log 2>&1 || echo "seed $seed $case: wifi-calibrate exit $? (forced; see calibrate-$tag.log)" >&2
    for cal in truth drive; do
      nice "$build/bin/csi-bearings" test$tag.rawlog /dev/null --calib calib-$tag-$cal \
        --csv aoa-$tag-$cal.csv.part -q > bearings-$tag-$cal.log 2>&1
      mv aoa-$tag-$cal.csv.part aoa-$tag-$cal.csv
    done
    rm -f cal$tag.rawlog test$tag.rawlog
  done
done
python3 - "$@" <<'PY'
import csv, sys
def load(tag, cal):
    truth = {}
    for r in csv.DictReader(open(f"truth{tag}/frames.csv")):
        truth[(r["mac"], round(float(r["timestamp_unix"]), 4))] = float(r["aoa_deg"])
    out = []
    for r in csv.DictReader(open(f"aoa-{tag}-{cal}.csv")):
        t = truth.get((r["transmitter"], round(float(r["timestamp"]), 4)))
        if t is None: continue
        a = float(r["aoa_deg"])
        # A linear array along y: the mirror across its axis (x -> -x) is equally consistent.
        e = min(abs((a - t + 180) % 360 - 180), abs((180 - a - t + 180) % 360 - 180))
        out.append((e, float(r["aoa_std_deg"])))
    return out
def line(name, v):
    if not v: print(f"{name}: no bearings"); return
    e = sorted(x for x, _ in v); n = len(e)
    q = lambda p: e[min(n - 1, int(p * n))]
    print(f"{name}: {n} AoA, median {q(.5):.2f} deg, p90 {q(.9):.2f} deg, "
          f">30 deg {100*sum(x > 30 for x in e)/n:.1f} %, within 3 sigma "
          f"{100*sum(x <= 3*s for x, s in v)/n:.1f} %")
for cal in ("truth", "drive"):
    for case in ("nojumps", "jumps"):
        pooled = []
        for seed in sys.argv[1:]:
            v = load(f"{case}{seed}", cal); pooled += v; line(f"seed {seed} {case:7s} {cal} offsets", v)
        line(f"all seeds {case:7s} {cal} offsets", pooled)
PY
