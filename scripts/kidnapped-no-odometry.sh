#!/usr/bin/env bash
# Kidnapped robot with and without odometry (issue 19.2), from the command-line tools alone:
# share/scenarios/kidnapped.yaml (5 x 10 m, 4 APs with 4-antenna arrays) at 10 frames/s per AP,
# a random drive at up to 0.5 m/s.
#   scripts/kidnapped-no-odometry.sh [--live] BUILD_DIR WORK_DIR SEED...
# Per seed: wifi-sim -d 60; receiver AoA from csi-bearings (default estimator, the simulator's
# true receiver offsets: bearing-accuracy --truth-calibration), for the run without odometry with
# the rawlog's odometry ignored (--no-odometry: its windows chosen without it, as on a robot that
# has none; before 2026-11-27 both runs used the bearings windowed with it); wifi-pf-localization with the
# drive's odometry and without (--max-speed 0.6, the shipped [UnknownMotion] and
# [ParticleRecovery]), 3000 particles, errors of the estimate (PF mean refined by the window
# smoother) against the true poses. Prints one line per seed and run (median error after
# convergence, worst error, estimates outside the room, recovery episodes), then the ratio
# without/with odometry per seed.
# --live: also wifi-localize, live, on the same drive streamed in real time by rt-ac86u-emulator
# on loopback (the CSI and, with odometry, the odometry stream; 2 x 65 s per seed), its own
# bearing chain configured as csi-bearings above; the same figures, which wifi-localize computes
# itself (-g: the true trajectory moved onto the receiver's clock through the emulator's
# unix_time_at_sim_zero), and the share of the estimates after convergence inside their own 95 %
# ellipse.
set -euo pipefail
live=0; [ "${1:-}" = --live ] && { live=1; shift; }
[ $# -ge 3 ] || { echo "usage: $0 [--live] BUILD_DIR WORK_DIR SEED..." >&2; exit 2; }
build=$(realpath "$1"); work=$2; shift 2
src=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work/scenarios"; cd "$work"
ln -sfn "$src/share/arrays" arrays
sed -e 's/frame_rate_hz: 100/frame_rate_hz: 10/' -e 's/speed_mps: 0.6/speed_mps: 0.5/' \
  "$src/share/scenarios/kidnapped.yaml" > scenarios/kidnapped-10hz.yaml
grep -q "frame_rate_hz: 10}" scenarios/kidnapped-10hz.yaml || { echo "kidnapped.yaml's frame rate changed" >&2; exit 1; }
ini="$src/share/localization/pf-localization-wifi.ini"
# One line of figures from a wifi-pf-localization or wifi-localize summary.txt (with -g).
report() {
  local s=$2 after conv worst outside rec cover
  after=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*max=\([0-9.]*\).*/\1 \2/p' $s)
  conv=$(sed -n 's/.*converged after: \([0-9.]*\) s.*/\1/p; s/.*converged after: never.*/never/p' $s)
  worst=$(sed -n 's/.*error (all).*max=\([0-9.]*\).*/\1/p' $s)
  outside=$(sed -n 's/.*, \([0-9]*\) estimates outside it.*/\1/p' $s)
  rec=$(sed -n 's/.*recovery .*: \([0-9]*\) episodes.*/\1/p' $s)
  cover=$(sed -n 's/.*in 95 % ellipse: \([0-9.]*\) %.*/\1/p' $s)
  echo "$1: converged after ${conv:-?} s, median after ${after%% *} m, worst after ${after##* } m, worst overall $worst m, ${outside:-?} estimates outside the room, ${rec:-0} recovery episodes${cover:+, $cover % inside their 95 % ellipse}"
}
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
    report "seed $seed $run" pf-$run-$seed/summary.txt
  done
  mo=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*/\1/p' pf-odometry-$seed/summary.txt)
  mn=$(sed -n 's/.*after converged:.*median=\([0-9.]*\).*/\1/p' pf-none-$seed/summary.txt)
  [ -n "$mo" ] && [ -n "$mn" ] && python3 -c "print('seed $seed: without / with odometry %.2fx' % ($mn / $mo))"
  [ $live = 1 ] || continue
  for run in odometry none; do
    out=live-$run-$seed; rm -rf $out $out.state; mkdir -p $out.state
    read -r csiPort odoPort < <(python3 -c "
import socket
s = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2)]
for x in s: x.bind(('127.0.0.1', 0))
print(*[x.getsockname()[1] for x in s])")
    # The emulator example .ini with this seed's map, ports and bearing chain (as csi-bearings
    # above); without odometry its [ODOMETRY] sensor is left out.
    python3 -c "import sys; sys.path.insert(0, sys.argv[1]); from pf_rooms import derive_ini
derive_ini(sys.argv[2], sys.argv[3], sys.argv[5:], drop=['ODOMETRY'] if sys.argv[4] == 'none' else [])" \
      "$src/scripts" "$src/share/localization/wifi-localize-emulator.ini" $out.ini $run \
      WIFI_CSI/udp_port=$csiPort ODOMETRY/udp_port=$odoPort \
      wifi-localize/bearing_algorithm=default wifi-localize/bearing_calibration="$(pwd)/calib$seed" \
      wifi-localize/bearing_array="$src/share/arrays/rt-ac86u.yaml" \
      wifi-localize/bearing_tx_arrays="$src/share/arrays/ap-linear-4.yaml" \
      MetricMap_wifiBearingMap_00_creationOpts/transmitters_file="$(pwd)/truth$seed/transmitters.yaml" \
      MetricMap_wifiBearingMap_00_likelihoodOpts/use_aoa=true \
      MetricMap_wifiBearingMap_00_likelihoodOpts/use_aod=false UnknownMotion/max_speed_mps=0.6
    odoArgs=(); [ $run = odometry ] && odoArgs=(--odometry-port $odoPort)
    # --scenario-seed: the world wifi-sim -s $seed drew above (the truth and the calibration).
    "$build/bin/rt-ac86u-emulator" --scenario scenarios/kidnapped-10hz.yaml --scenario-seed $seed --preconfigured 155/80 -q \
      --port $csiPort --dest 127.0.0.1 --state-dir $out.state --duration 65 "${odoArgs[@]}" > $out.emulator.log 2>&1 &
    emu=$!
    for _ in $(seq 200); do [ -S $out.state/emulator.sock ] && break; sleep 0.025; done
    # wifi-localize scores its estimate itself (-g): the true trajectory moved onto the
    # receiver's clock, the simulation's zero being the emulator's unix_time_at_sim_zero.
    zero=$($out.state/bin/emulator-ctl status | python3 -c "import json, sys
print(json.load(sys.stdin)['emulator']['unix_time_at_sim_zero'])") ||
      { echo "seed $seed live $run: the emulator did not start ($out.emulator.log)"; kill $emu; continue; }
    awk -v zero=$zero '/^#/ { print; next } !n++ { t0 = $1 } { $1 = sprintf("%.6f", zero + $1 - t0); print }' \
      truth$seed/trajectory_tum.txt > $out.truth.txt
    timeout 120 "$build/bin/wifi-localize" -p "$build/lib/libmrpt_wifi_sensor.so" $out.ini -q -o $out -d 60 \
      --stop-when-idle 3 -g $out.truth.txt > $out.log 2>&1 || echo "seed $seed live $run: wifi-localize failed ($out.log)"
    kill -TERM $emu 2>/dev/null || true; wait $emu 2>/dev/null || true
    [ -f $out/summary.txt ] && report "seed $seed live $run" $out/summary.txt
  done
done
