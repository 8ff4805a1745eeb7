#!/usr/bin/env bash
# Re-runs one live run of a localization-accuracy room with another filter seed, as the
# evaluator runs it (the room's recorded live .ini and scenario; wifi-localize started first and
# rt-ac86u-emulator, once it listens, streaming in real time on loopback, so the run gets the
# drive from its first frame), and prints its median error after convergence
# against the true poses (pf_rooms.py's figure; the emulator's truth, written on the receiver's
# clock, as the estimate).
#
#   scripts/live_rerun.sh BUILD_DIR ROOM_DIR live-odometry|live-no-odometry SEED OUT_DIR
#
# ROOM_DIR is a room-N folder of `localization-accuracy -w DIR` (live runs not skipped). The
# live run takes the drive's duration (40 s by default), so run one at a time.
set -euo pipefail
if [[ $# -ne 5 ]]; then
    sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
build=$1 room=$2 run=$3 seed=$4 out=$5
ini=$room/$run.ini
[[ -f $ini ]] || { echo "live_rerun.sh: $ini: not found (a sweep run with --no-live?)" >&2; exit 2; }
port=$(awk -F= '/^\[/{s=($0=="[WIFI_CSI]")} s && $1 ~ /^udp_port *$/ {gsub(/ /,"",$2); print $2}' "$ini")
odoPort=$(awk -F= '/^\[/{s=($0=="[ODOMETRY]")} s && $1 ~ /^udp_port *$/ {gsub(/ /,"",$2); print $2}' "$ini")
[[ -n $port ]] || { echo "live_rerun.sh: $ini: no [WIFI_CSI] udp_port" >&2; exit 2; }
mkdir -p "$out"
state=$(mktemp -d)
trap 'rm -rf "$state"' EXIT
emuArgs=(--port "$port" --dest 127.0.0.1 --state-dir "$state" --duration 50 --status-period 1
    --scenario "$room/kidnapped/scenario.yaml" --preconfigured 155/80 -q)
[[ $run == live-odometry && -n $odoPort ]] && emuArgs+=(--odometry-port "$odoPort")
timeout 130 "$build/bin/wifi-localize" -p "$build/lib/libmrpt_wifi_sensor.so" "$ini" -q -o "$out" \
    -d 70 --stop-when-idle 3 --seed "$seed" >"$out/wifi-localize.log" 2>&1 &
live=$!
# Bound to its UDP port (/proc/net/udp: local address hex IP:PORT) before the stream starts.
hexPort=$(printf ':%04X ' "$port")
for _ in $(seq 1200); do
    grep -q "$hexPort" /proc/net/udp /proc/net/udp6 2>/dev/null && break
    kill -0 "$live" 2>/dev/null || break
    sleep 0.025
done
"$build/bin/rt-ac86u-emulator" "${emuArgs[@]}" >"$out/emulator.log" 2>&1 &
emu=$!
status=0
wait "$live" || status=$?
kill "$emu" 2>/dev/null || true
wait "$emu" 2>/dev/null || true
if [[ $status -ne 0 ]]; then
    echo "live_rerun.sh: wifi-localize exited $status (see $out/wifi-localize.log)" >&2
    exit 1
fi
cp "$state/summary.json" "$out/"
# The emulator's ground truth, on the receiver's clock (as estimate_tum.txt): no shift needed.
cp "$state/truth/trajectory_tum.txt" "$out/truth_tum.txt"
python3 - "$room" "$out" "$(dirname "$0")" <<'EOF'
import os, sys
room, out, scripts = sys.argv[1:]
sys.path.insert(0, scripts)
import pf_rooms
truth = pf_rooms.read_tum(os.path.join(out, "truth_tum.txt"))
median = pf_rooms.median_after_convergence(pf_rooms.read_tum(os.path.join(out, "estimate_tum.txt")), truth)
print(f"{os.path.basename(room)} {os.path.basename(out)}: median error after convergence "
      + ("never converged" if median == float("inf") else f"{median:.2f} m"))
EOF
