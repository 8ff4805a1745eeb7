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
# bearing chain configured as csi-bearings above; the same figures from its estimate_tum.txt (on
# the simulation's clock through the emulator's unix_time_at_sim_zero), and the share of the
# estimates after convergence inside their own 95 % ellipse (estimate_cov.csv).
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
  [ $live = 1 ] || continue
  sed "s/^seed: .*/seed: $seed/" scenarios/kidnapped-10hz.yaml > scenarios/kidnapped-10hz-$seed.yaml
  grep -q "^seed: $seed$" scenarios/kidnapped-10hz-$seed.yaml || { echo "no seed key in kidnapped.yaml" >&2; exit 1; }
  for run in odometry none; do
    out=live-$run-$seed; rm -rf $out $out.state; mkdir -p $out.state
    read -r csiPort odoPort < <(python3 -c "
import socket
s = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2)]
for x in s: x.bind(('127.0.0.1', 0))
print(*[x.getsockname()[1] for x in s])")
    # The emulator example .ini with this seed's map, ports and bearing chain (as csi-bearings
    # above); without odometry its [ODOMETRY] sensor is left out.
    python3 - "$src/share/localization/wifi-localize-emulator.ini" $out.ini $run "$(pwd)" $seed $csiPort $odoPort <<'PY'
import re, sys
src, dst, run, work, seed, csi, odo = sys.argv[1:]
keys = {("WIFI_CSI", "udp_port"): csi, ("ODOMETRY", "udp_port"): odo,
        ("wifi-localize", "bearing_algorithm"): "default",
        ("wifi-localize", "bearing_calibration"): f"{work}/calib{seed}",
        ("MetricMap_wifiBearingMap_00_creationOpts", "transmitters_file"): f"{work}/truth{seed}/transmitters.yaml",
        ("MetricMap_wifiBearingMap_00_likelihoodOpts", "use_aoa"): "true",
        ("MetricMap_wifiBearingMap_00_likelihoodOpts", "use_aod"): "false",
        ("UnknownMotion", "max_speed_mps"): "0.6"}
if run == "none":
    del keys[("ODOMETRY", "udp_port")]
out, section, headers = [], None, {}
for line in open(src):
    m = re.match(r"\s*\[(.+)\]", line)
    if m:
        section = m.group(1)
        headers[section] = len(out)
    if run == "none" and section == "ODOMETRY":
        continue
    k = re.match(r"\s*([A-Za-z_0-9]+)\s*=", line)
    if k and (section, k.group(1)) in keys:
        line = f"{k.group(1)} = {keys.pop((section, k.group(1)))}\n"
    out.append(line.replace("= ../arrays/", f"= {work}/arrays/"))  # relative to the example's folder
for section, _ in keys:
    if section not in headers:
        sys.exit(f"{src}: no section [{section}]")
# keys the example leaves out: added under their section's header, the last section first
for (section, key), value in sorted(keys.items(), key=lambda kv: -headers[kv[0][0]]):
    out.insert(headers[section] + 1, f"{key} = {value}\n")
open(dst, "w").writelines(out)
PY
    odoArgs=(); [ $run = odometry ] && odoArgs=(--odometry-port $odoPort)
    "$build/bin/rt-ac86u-emulator" --scenario scenarios/kidnapped-10hz-$seed.yaml --preconfigured 155/80 -q \
      --port $csiPort --dest 127.0.0.1 --state-dir $out.state --duration 65 "${odoArgs[@]}" > $out.emulator.log 2>&1 &
    emu=$!
    for _ in $(seq 200); do [ -S $out.state/emulator.sock ] && break; sleep 0.025; done
    timeout 120 "$build/bin/wifi-localize" -p "$build/lib/libmrpt_wifi_sensor.so" $out.ini -q -o $out -d 60 \
      --stop-when-idle 3 > $out.log 2>&1 || echo "seed $seed live $run: wifi-localize failed ($out.log)"
    kill -TERM $emu 2>/dev/null || true; wait $emu 2>/dev/null || true
    python3 - $out truth$seed/trajectory_tum.txt $out.state/summary.json "seed $seed live $run" <<'PY' || true
import bisect, json, math, re, statistics, sys
out, truth_file, summary, name = sys.argv[1:]
try:
    zero = json.load(open(summary))["emulator"]["unix_time_at_sim_zero"]
    est = [list(map(float, l.split()[:3])) for l in open(f"{out}/estimate_tum.txt") if not l.startswith("#")]
    cov = [l.split(",") for l in open(f"{out}/estimate_cov.csv")][1:]
except (OSError, KeyError, ValueError) as e:
    sys.exit(f"{name}: no live estimate ({e})")
truth = [list(map(float, l.split()[:3])) for l in open(truth_file) if not l.startswith("#")]
tt = [r[0] for r in truth]
times, errs, inside = [], [], []
for i, (t, x, y) in enumerate(est):
    t = tt[0] + (t - zero)  # the receiver's clock -> the simulation's
    j = bisect.bisect_left(tt, t)
    if j == 0 or j >= len(tt):
        continue
    a = (t - tt[j - 1]) / (tt[j] - tt[j - 1])
    ex = x - (truth[j - 1][1] + a * (truth[j][1] - truth[j - 1][1]))
    ey = y - (truth[j - 1][2] + a * (truth[j][2] - truth[j - 1][2]))
    times.append(t)
    errs.append(math.hypot(ex, ey))
    if len(cov) == len(est):
        sx, sy, r = float(cov[i][4]), float(cov[i][5]), float(cov[i][6])
        cxx, cyy, cxy = sx * sx, sy * sy, r * sx * sy
        det = cxx * cyy - cxy * cxy
        inside.append(det > 0 and (cyy * ex * ex - 2 * cxy * ex * ey + cxx * ey * ey) / det <= 5.991)
# converged: the first estimate from which the error stays below 1 m for 5 s
first, start = None, 0
for i, e in enumerate(errs):
    if e >= 1.0:
        start = i + 1
    elif times[i] - times[start] >= 5.0:
        first = start
        break
if first is None:
    print(f"{name}: never converged ({len(errs)} estimates)")
    sys.exit()
after = errs[first:]
cover = f", {100 * sum(inside[first:]) / len(after):.1f} % inside their 95 % ellipse" if inside else ""
outside = re.search(r"area +:.*, (\d+) estimates outside it", open(f"{out}/summary.txt").read())
print(f"{name}: converged after {times[first] - times[0]:.1f} s, median after {statistics.median(after):.3f} m, "
      f"worst after {max(after):.3f} m, worst overall {max(errs):.3f} m, "
      f"{outside.group(1) if outside else '?'} estimates outside the room{cover}")
PY
  done
done
