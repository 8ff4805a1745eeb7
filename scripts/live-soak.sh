#!/usr/bin/env bash
# Live soak at building scale (issue 56, item 3; not in CI: it takes MINUTES*60/SPEED seconds).
# rt-ac86u-emulator streams share/scenarios/building-hopping.yaml (60 x 30 m, 16 single-stream
# APs at 10 frames/s each on 42/80, 155/80 and 6/20, drifting wheel odometry) accelerated by
# SPEED to wifi-localize, whose CWiFiCSISensor configures the emulated router over a loopback
# sshd and hops between the three channels (channel_schedule), makes the bearings itself
# (bearing_algorithm = default, the simulator's true receive calibration of each channel) and
# feeds the particle filter with the odometry. Every SAMPLE wall seconds it records the resident
# memory of wifi-localize (VmRSS, the sensor runs inside it) against the emulator's simulated
# time. At the end it prints the lag percentiles wifi-localize measured, the RSS at data minutes
# 10 and 60 (or the last sample when the run is shorter) and the growth between them, the
# frames each AP got out of the emulator against those wifi-localize received, the lag of the
# status lines per 10 data minutes (flat or not) and the error against the emulator's ground
# truth (scored here: wifi-localize -g would keep every estimate until the end).
# Figures and what they mean: docs/evaluation.md, "An hour at building scale".
# Exit status 0: targets met (lag p99 <= 100 ms, RSS growth < 10 %); 1: a target missed; 2: the
# run failed.
#
# Under --speed everything is stamped on the receiver's (wall) clock: the CSI and odometry on
# arrival, the emulator's ground truth when the simulated instant is sent. A data second is
# 1/SPEED wall seconds, so the lag (pose output time - newest bearing's arrival) stays a real
# latency. Settings given in seconds are scaled by 1/SPEED so that each works on the data it
# would in real time (rates multiplied): the channel dwell (2 data s), the window smoother's
# window and period, [ParticleRecovery] window_s and rate_hz.
set -euo pipefail
usage() {
  cat <<'EOF'
usage: scripts/live-soak.sh [options] [OUT_DIR]   (default OUT_DIR: live-soak-output)
  --minutes M      simulated minutes to replay (default 60; the scenario is an hour long)
  --speed S        simulated seconds per wall second (default 4: an hour in 15 min)
  --dwell S        seconds of DATA on each channel of the schedule (default 2)
  --sample S       wall seconds between memory samples (default 10)
  --particles N    particle count (default 3000)
  --build DIR      build folder with bin/ and lib/ (default: the repository's build/)
  --max-lag-ms X   p99 lag target (default 100)
  --max-growth P   RSS growth target, % from minute 10 to minute 60 (default 10)
  -h, --help       this text
Run it with `nice`; an hour at --speed 4 is 15 minutes of wall time.
EOF
}
minutes=60 speed=4 dwell=2 sample=10 particles=3000 maxLag=100 maxGrowth=10
src=$(cd "$(dirname "$0")/.." && pwd)
build=$src/build out=live-soak-output
while [ $# -gt 0 ]; do
  case $1 in
    --minutes) minutes=$2; shift 2 ;;
    --speed) speed=$2; shift 2 ;;
    --dwell) dwell=$2; shift 2 ;;
    --sample) sample=$2; shift 2 ;;
    --particles) particles=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --max-lag-ms) maxLag=$2; shift 2 ;;
    --max-growth) maxGrowth=$2; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    -*) echo "live-soak: unknown option $1" >&2; usage >&2; exit 2 ;;
    *) out=$1; shift ;;
  esac
done
for v in minutes speed dwell sample particles maxLag maxGrowth; do
  python3 -c "import sys; v = float(sys.argv[1]); sys.exit(0 if v > 0 else 1)" "${!v}" 2>/dev/null ||
    { echo "live-soak: --$v '${!v}' must be a number > 0" >&2; exit 2; }
done
build=$(realpath "$build"); bin=$build/bin; lib=$build/lib
# A copy of a build folder works too (its libraries before the RUNPATH's).
export LD_LIBRARY_PATH=$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
for f in "$bin/rt-ac86u-emulator" "$bin/wifi-localize" "$bin/bearing-accuracy" "$lib/libmrpt_wifi_sensor.so"; do
  [ -e "$f" ] || { echo "live-soak: $f missing (build first: scripts/build.sh)" >&2; exit 2; }
done
scenario=$src/share/scenarios/building-hopping.yaml
seed=56  # the scenario's own seed: the world of the truth calibration below
out=$(realpath -m "$out"); rm -rf "$out"; mkdir -p "$out"; cd "$out"
f() { python3 -c "print(repr(float(eval('$1'))))"; }  # arithmetic on decimals
wall=$(f "$minutes * 60 / $speed")

pids=()
cleanup() { for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done; }
trap cleanup EXIT

# The receive calibration of every channel: the simulator's true chain offsets (as a calibration
# drive would give them; issue 56's per-channel calibration is measured elsewhere).
"$bin/bearing-accuracy" --truth-calibration "$scenario" calib --seed $seed >calib.log 2>&1 ||
  { echo "live-soak: bearing-accuracy --truth-calibration failed (calib.log)" >&2; exit 2; }

read -r csiPort odoPort < <(python3 -c "
import socket
s = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2)]
for x in s: x.bind(('127.0.0.1', 0))
print(*[x.getsockname()[1] for x in s])")

# The emulator starts with the router unconfigured: wifi-localize's sensor sets it up over ssh
# and switches channels with the router's own tools.
"$bin/rt-ac86u-emulator" --scenario "$scenario" --scenario-seed $seed --speed "$speed" \
  --port "$csiPort" --odometry-port "$odoPort" --dest 127.0.0.1 --state-dir "$out/emulator" \
  --duration "$(f "$wall + 10")" --status-period 60 >emulator.json 2>emulator.log &
emu=$!; pids+=($emu)
for _ in $(seq 200); do [ -S emulator/emulator.sock ] && break; sleep 0.05; done
[ -S emulator/emulator.sock ] || { echo "live-soak: the emulator did not start (emulator.log)" >&2; exit 2; }
# shellcheck source=loopback-sshd.sh
source "$src/scripts/loopback-sshd.sh"
start_loopback_sshd "$out/sshd" "$out/emulator/bin" || exit 2
pids+=("$SSHD_PID")

ini=$out/wifi-localize.ini
python3 -c "import sys; sys.path.insert(0, sys.argv[1]); from pf_rooms import derive_ini
derive_ini(sys.argv[2], sys.argv[3], sys.argv[4:])" "$src/scripts" \
  "$src/share/localization/wifi-localize-emulator.ini" "$ini" \
  WIFI_CSI/udp_port=$csiPort ODOMETRY/udp_port=$odoPort \
  WIFI_CSI/router_control=true WIFI_CSI/login_host=127.0.0.1 WIFI_CSI/login_port=$SSHD_PORT \
  WIFI_CSI/login_user="$(id -un)" WIFI_CSI/login_identity_file="$SSHD_KEY" \
  WIFI_CSI/login_known_hosts="$SSHD_KNOWN_HOSTS" \
  "WIFI_CSI/channel_schedule=42/80 155/80 6/20" WIFI_CSI/channel_dwell_s="$(f "$dwell / $speed")" \
  WIFI_CSI/bearing_algorithm=default WIFI_CSI/bearing_calibration="$out/calib" \
  WIFI_CSI/bearing_array="$src/share/arrays/rt-ac86u.yaml" \
  wifi-localize/bearing_algorithm= \
  MetricMap_wifiBearingMap_00_creationOpts/transmitters_file="$out/emulator/truth/transmitters.yaml" \
  MetricMap_wifiBearingMap_00_likelihoodOpts/use_aoa=true \
  MetricMap_wifiBearingMap_00_likelihoodOpts/use_aod=false \
  LocalizationExperiment/particles_count=$particles KLD_options/KLD_minSampleSize=$particles \
  KLD_options/KLD_maxSampleSize=$particles \
  LocalizationExperiment/init_PDF_max_x=60 LocalizationExperiment/init_PDF_max_y=30 \
  WindowSmoother/window_s="$(f "20 / $speed")" WindowSmoother/min_window_s="$(f "5 / $speed")" \
  WindowSmoother/solve_period_s="$(f "0.5 / $speed")" \
  ParticleRecovery/window_s="$(f "2 / $speed")" ParticleRecovery/rate_hz="$(f "1 * $speed")"

# LIVE_SOAK_WRAPPER (diagnosis only; the RSS is then the wrapper's): e.g. "heaptrack -o FILE".
${LIVE_SOAK_WRAPPER:-} "$bin/wifi-localize" -p "$lib/libmrpt_wifi_sensor.so" "$ini" -o "$out/wifi-localize" \
  -d "$(f "$wall + 60")" --stop-when-idle 5 \
  >wifi-localize.summary 2>wifi-localize.log &
wl=$!; pids+=($wl)

# Memory against simulated time (the emulator's clock: minute m of the data).
# CPU: seconds of user + system time so far (wifi-localize, emulator).
cpu() { awk -v hz="$(getconf CLK_TCK)" '{ print ($14 + $15) / hz }' /proc/$1/stat 2>/dev/null || true; }
echo "wall_s,sim_s,rss_kib,wifi_localize_cpu_s,emulator_cpu_s,load_1min" >rss.csv
start=$(date +%s.%N)
while kill -0 $wl 2>/dev/null; do
  rss=$(awk '/^VmRSS/ {print $2}' /proc/$wl/status 2>/dev/null || true)
  sim=$(emulator/bin/emulator-ctl status 2>/dev/null |
    python3 -c "import json, sys; print(json.load(sys.stdin)['emulator']['sim_time_s'])" 2>/dev/null || true)
  cpuWl=$(cpu $wl); cpuEmu=$(cpu $emu)
  [ -n "$rss" ] && [ -n "$sim" ] && [ -n "$cpuWl" ] && [ -n "$cpuEmu" ] &&
    echo "$(f "$(date +%s.%N) - $start"),$sim,$rss,$cpuWl,$cpuEmu,$(cut -d' ' -f1 /proc/loadavg)" >>rss.csv
  printf '\rlive-soak: data minute %5.1f of %s, wifi-localize RSS %s KiB ' \
    "$(f "${sim:-0} / 60")" "$minutes" "${rss:--}"
  sleep "$sample"
done
echo
wait $wl && status=0 || status=$?
kill -TERM $emu 2>/dev/null || true; wait $emu 2>/dev/null || true
kill -TERM "$SSHD_PID" 2>/dev/null || true
if [ $status -ne 0 ]; then
  echo "live-soak: wifi-localize exited with status $status (wifi-localize.log)" >&2; exit 2
fi

python3 - "$out" "$minutes" "$speed" "$maxLag" "$maxGrowth" <<'PY'
import csv, json, os, re, sys
out, minutes, speed, max_lag, max_growth = sys.argv[1], float(sys.argv[2]), *map(float, sys.argv[3:])
# wifi-localize's stdout: its summary, among the sensor's log lines (MRPT's logger).
summary = open(f"{out}/wifi-localize.summary").read()
summary = "".join(l for l in summary[summary.find("wifi-localize summary"):].splitlines(True)
                  if not l.startswith("["))
print(summary, end="")
lag = re.search(r"lag \[ms\]\s*: p50 ([0-9.]+), p99 ([0-9.]+), max ([0-9.]+)", summary)
p50, p99, lmax = map(float, lag.groups())
samples = list(csv.DictReader(open(f"{out}/rss.csv")))
rows = [(float(r["sim_s"]) / 60, int(r["rss_kib"])) for r in samples]
def at(minute):  # the sample nearest to that data minute
    return min(rows, key=lambda r: abs(r[0] - minute))
# Minutes 10 and 60; a shorter run: its first sixth (warm-up) and its last sample.
first = at(10) if rows[-1][0] >= 20 else at(rows[-1][0] / 6)
last = at(60) if rows[-1][0] >= 59.5 else rows[-1]
growth = 100.0 * (last[1] - first[1]) / first[1]
emu = json.load(open(f"{out}/emulator/summary.json"))
# The lag of the status lines (the newest pose's, once a second) per 10 data minutes: flat?
samples_wall = [float(r["wall_s"]) for r in samples]
sim0 = float(samples[0]["sim_s"]) - speed * samples_wall[0]
per10 = {}
for m in re.finditer(r"\[wifi-localize\] t=([0-9.]+)s .* lag=([0-9]+)ms", open(f"{out}/wifi-localize.log").read()):
    minute = (sim0 + speed * float(m.group(1))) / 60
    per10.setdefault(int(minute // 10), []).append(float(m.group(2)))
def pct(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * len(v)))]
# The estimate against the emulator's ground truth (both on the receiver's clock), after the
# first data minute. Scored here rather than with wifi-localize -g, which keeps every estimate
# until the end: the soak measures the memory of a run without it.
truth = [list(map(float, l.split()[:3])) for l in open(f"{out}/emulator/truth/trajectory_tum.txt") if not l.startswith("#")]
est = [list(map(float, l.split()[:3])) for l in open(f"{out}/wifi-localize/estimate_tum.txt") if not l.startswith("#")]
errs, j = [], 0
for t, x, y in est:
    while j + 1 < len(truth) and truth[j + 1][0] < t:
        j += 1
    if j + 1 >= len(truth) or t < truth[j][0] or t - est[0][0] < 60 / speed:
        continue
    (ta, xa, ya), (tb, xb, yb) = truth[j], truth[j + 1]
    f = (t - ta) / (tb - ta) if tb > ta else 0
    errs.append(((x - xa - f * (xb - xa)) ** 2 + (y - ya - f * (yb - ya)) ** 2) ** 0.5)
end = samples[-1]
wall = float(end["wall_s"])
print(f"speed {speed:g}: data minute {rows[-1][0]:.1f} reached after {wall:.0f} s wall; CPU "
      f"wifi-localize {100 * float(end['wifi_localize_cpu_s']) / wall:.0f} %, emulator "
      f"{100 * float(end['emulator_cpu_s']) / wall:.0f} % of one core; machine load (1 min) "
      f"{sum(float(r['load_1min']) for r in samples) / len(samples):.1f} on average, "
      f"{max(float(r['load_1min']) for r in samples):.1f} at most, {os.cpu_count()} cores")
print(f"lag [ms]: p50 {p50:.1f}, p99 {p99:.1f}, max {lmax:.1f} (target p99 <= {max_lag:g})")
print(f"RSS: minute {first[0]:.1f} {first[1]} KiB, minute {last[0]:.1f} {last[1]} KiB, growth {growth:+.1f} % "
      f"(target < {max_growth:g} %); peak {max(r[1] for r in rows)} KiB")
sent = emu["data_plane"].get("frames_emitted_by_transmitter", {})
line = re.search(r"^\s+CSI per sender :(.*)$", summary, re.M)
items = line.group(1).split() if line else []
got = {items[i].lower(): int(items[i + 1]) for i in range(0, len(items) - 1, 2)}
if sent:
    print("frames per AP, emitted by the emulator / received by wifi-localize:")
    for mac in sorted(sent):
        print(f"  {mac} {sent[mac]} / {got.get(mac.lower(), 0)}")
print(f"emulator: {emu['data_plane']['frames_emitted']} frames emitted, max lag {1e3 * emu['data_plane']['max_lag_s']:.1f} ms behind schedule")
print("lag per 10 data minutes [ms], p50 / p90 / max of the status lines' (the newest pose's, once a second): " +
      ", ".join(f"{10 * k}-{10 * k + 10}: {pct(v, 0.5):.0f} / {pct(v, 0.9):.0f} / {max(v):.0f}"
                for k, v in sorted(per10.items()) if len(v) >= 10))
if errs:
    print(f"error after the first data minute: median {pct(errs, 0.5):.3f} m, p90 {pct(errs, 0.9):.3f} m, "
          f"max {max(errs):.3f} m ({len(errs)} estimates)")
ok = p99 <= max_lag and growth < max_growth
print("live-soak: PASS" if ok else "live-soak: FAIL (target missed)")
sys.exit(0 if ok else 1)
PY
