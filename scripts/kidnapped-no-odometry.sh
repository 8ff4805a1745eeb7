#!/usr/bin/env bash
# Kidnapped robot with and without odometry (issue 19.2), from the command-line tools alone:
# share/scenarios/kidnapped.yaml (5 x 10 m, 4 APs with 4-antenna arrays) at 10 frames/s per AP,
# a random drive at up to 0.5 m/s.
#   scripts/kidnapped-no-odometry.sh BUILD_DIR WORK_DIR SEED...
# Per seed: wifi-sim -d 60; receiver AoA from csi-bearings (default estimator, the simulator's
# true receiver offsets: bearing-accuracy --truth-calibration), for the run without odometry with
# the rawlog's odometry ignored (--no-odometry: its windows chosen without it, as on a robot that
# has none; before 2026-11-27 both runs used the bearings windowed with it); wifi-pf-localization with the
# drive's odometry and without (--max-speed 0.6, the shipped [UnknownMotion] and
# [ParticleRecovery]), 3000 particles, errors of the estimate (PF mean refined by the window
# smoother) against the true poses. Prints one line per seed and run (median error after
# convergence, worst error, estimates outside the room, recovery episodes), then the ratio
# without/with odometry per seed.
set -euo pipefail
build=$(realpath "$1"); work=$2; shift 2
src=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work/scenarios"; cd "$work"
ln -sfn "$src/share/arrays" arrays
sed -e 's/frame_rate_hz: 100/frame_rate_hz: 10/' -e 's/speed_mps: 0.6/speed_mps: 0.5/' \
  "$src/share/scenarios/kidnapped.yaml" > scenarios/kidnapped-10hz.yaml
grep -q "frame_rate_hz: 10}" scenarios/kidnapped-10hz.yaml || { echo "kidnapped.yaml's frame rate changed" >&2; exit 1; }
ini="$src/share/localization/pf-localization-wifi.ini"
for seed in "$@"; do
  if [ ! -f bearings$seed.csv ] || [ ! -f bearings-none$seed.csv ]; then
    nice "$build/bin/wifi-sim" scenarios/kidnapped-10hz.yaml d$seed.rawlog -t truth$seed -s $seed -d 60 -q
    nice "$build/bin/bearing-accuracy" --truth-calibration scenarios/kidnapped-10hz.yaml calib$seed --seed $seed >/dev/null
    nice "$build/bin/csi-bearings" d$seed.rawlog /dev/null --calib calib$seed --csv bearings$seed.csv.part -q \
      > bearings$seed.log 2>&1
    nice "$build/bin/csi-bearings" d$seed.rawlog /dev/null --calib calib$seed --csv bearings-none$seed.csv.part \
      --no-odometry -q > bearings-none$seed.log 2>&1
    mv bearings$seed.csv.part bearings$seed.csv
    mv bearings-none$seed.csv.part bearings-none$seed.csv
    rm -f d$seed.rawlog
  fi
  for run in odometry none; do
    motion="--odometry-tum truth$seed/odometry_tum.txt"; bearings=bearings$seed.csv
    [ $run = none ] && motion="--max-speed 0.6" && bearings=bearings-none$seed.csv
    nice "$build/bin/wifi-pf-localization" "$ini" -q --no-plots -n 3000 -m truth$seed/transmitters.yaml \
      -b $bearings --sensor-pose 0.1 0 0.4 0 0 0 -g truth$seed/trajectory_tum.txt $motion \
      -o pf-$run-$seed > pf-$run-$seed.log 2>&1 || { echo "seed $seed $run: wifi-pf-localization failed (pf-$run-$seed.log)"; continue; }
    s=pf-$run-$seed/summary.txt
    after=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*max=\([0-9.]*\).*/\1 \2/p' $s)
    conv=$(sed -n 's/.*converged after: \([0-9.]*\) s.*/\1/p; s/.*converged after: never.*/never/p' $s)
    worst=$(sed -n 's/.*error (all).*max=\([0-9.]*\).*/\1/p' $s)
    outside=$(sed -n 's/.*, \([0-9]*\) estimates outside it.*/\1/p' $s)
    rec=$(sed -n 's/.*recovery .*: \([0-9]*\) episodes.*/\1/p' $s)
    echo "seed $seed $run: converged after ${conv:-?} s, median after ${after%% *} m, worst after ${after##* } m, worst overall $worst m, ${outside:-?} estimates outside the room, ${rec:-0} recovery episodes"
  done
  mo=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*/\1/p' pf-odometry-$seed/summary.txt)
  mn=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*/\1/p' pf-none-$seed/summary.txt)
  [ -n "$mo" ] && [ -n "$mn" ] && python3 -c "print('seed $seed: without / with odometry %.2fx' % ($mn / $mo))"
done
