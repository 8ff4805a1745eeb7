#!/usr/bin/env bash
# The end-to-end demo: installs what is needed, builds, then runs the whole story with no
# hardware (about 4 minutes once built; outputs and PNG plots in demo-output/, or $DEMO_OUT):
#   1. record: an emulated RT-AC86U (robot among 4 access points, share/scenarios/kidnapped.yaml)
#      sends Nexmon CSI to 127.0.0.1 and is configured over ssh (a throw-away sshd on
#      127.0.0.1) by Debian's rawlog-grabber with the CWiFiCSISensor plugin;
#      Debian's rawlog-edit reads the recording through the observation plugin;
#   2. calibrate: a short simulated drive of the same router near a known transmitter ->
#      wifi-calibrate -> the phase calibration file and its report; then a drive among the four
#      access points -> wifi-calibrate --transmit-chains -> each AP's transmit-chain phases
#      (without them csi-bearings reports no AoD: every real AP's chains have unknown phases);
#   3. bearings: csi-bearings turns the recording into AoA/AoD bearings (both sides calibrated);
#   4. kidnapped robot: wifi-pf-localization (MRPT's particle filter + CWiFiBearingMap);
#      then live: the emulator (CSI + its odometry stream) -> wifi-localize --view for 30 s
#      under Xvfb, screenshot in live/live_view.png;
#   5. drift correction: wifi-graphslam on a long drifting drive (share/scenarios/loop.yaml);
#   6. device mapping: wifi-iot-map on share/scenarios/iot.yaml (its own 2.4 GHz calibration);
#   7. a tcpdump capture (share/samples/, the project's encoder) -> rawlog (csi-import).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh

out=$(realpath -m "${DEMO_OUT:-demo-output}")
rm -rf "$out"; mkdir -p "$out"
bin=$PWD/build/bin
lib=$PWD/build/lib
share=$PWD/share
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT

echo "== 1. Record: emulated RT-AC86U + sshd on 127.0.0.1 + Debian's rawlog-grabber"
record_s=${DEMO_RECORD_SECONDS:-30}
port=$((20000 + RANDOM % 20000))
"$bin/rt-ac86u-emulator" --scenario "$share/scenarios/kidnapped.yaml" --port "$port" --dest 127.0.0.1 \
  --state-dir "$out/router" --duration $((record_s + 30)) --status-period 0 >"$out/emulator.log" 2>&1 &
emulator_pid=$!
pids+=("$emulator_pid")
sleep 1
source scripts/loopback-sshd.sh
start_loopback_sshd "$out/sshd" "$out/router/bin"   # sets SSHD_PORT, SSHD_KEY, SSHD_KNOWN_HOSTS
pids+=("$SSHD_PID")

sed -e "s|^login_host *=.*|login_host = 127.0.0.1|" -e "s|^login_port *=.*|login_port = $SSHD_PORT|" \
    -e "s|^login_user *=.*|login_user = $(id -un)|" -e "s|^login_identity_file *=.*|login_identity_file = $SSHD_KEY|" \
    -e "s|^login_known_hosts *=.*|login_known_hosts = $SSHD_KNOWN_HOSTS|" \
    -e "s|^udp_port *=.*|udp_port = $port|" -e "s|^udp_bind_address *=.*|udp_bind_address = 127.0.0.1|" \
    -e "s|^router_address *=.*|router_address = 127.0.0.1|" -e "s|^channel *=.*|channel = 155/80|" \
    -e "s|^rawlog_prefix *=.*|rawlog_prefix = recording|" -e "s|^status_period *=.*|status_period = 5|" \
    "$share/rawlog-grabber/csi_receiver.ini" >"$out/grab.ini"
(cd "$out" && (sleep "$record_s"; echo) | rawlog-grabber -p "$lib/libmrpt_wifi_sensor.so" grab.ini >grabber.log 2>&1)
grep -E "CWiFiCSISensor" "$out/grabber.log" | cut -c1-200 | tail -4
recording=$(ls "$out"/recording_*.rawlog)
kill -TERM "$emulator_pid" 2>/dev/null || true; wait "$emulator_pid" 2>/dev/null || true
rawlog-edit -p "$lib/libmrpt_wifi_obs.so" --info -i "$recording" 2>/dev/null | grep -E "objects|labels"
"$bin/csi-export" "$recording" --stats -q 2>/dev/null
# The robot's true path during the recording, on the recording's clock: the emulator writes it
# (STATE_DIR/truth/trajectory_tum.txt) as it runs.

echo "== 2. Calibrate: a 60 s drive of the same router (seed 7) near a transmitter at a known place"
"$bin/wifi-sim" "$share/scenarios/calibration.yaml" "$out/calibration_drive.rawlog" --seed 7 -d 60 \
  -t "$out/calibration_truth" -q >/dev/null
"$bin/wifi-calibrate" "$out/calibration_drive.rawlog" --array "$share/arrays/rt-ac86u.yaml" \
  --transmitters "$out/calibration_truth/transmitters.yaml" --poses "$out/calibration_truth/trajectory_tum.txt" \
  --out "$out/calib" --report "$out/calib_report" -q
rm -f "$out/calibration_drive.rawlog"
# The access points' transmit chains (phase per chain, per boot and channel): a 40 s drive among
# the same four APs (kidnapped.yaml, seed 7, the APs the emulator plays), true poses. Two APs
# are seen from fewer than 6 distinct 10-degree bearings on this drive: wifi-calibrate warns
# and --force writes them (their AoD error on the drive drops to 2-3 deg median).
"$bin/wifi-sim" "$share/scenarios/kidnapped.yaml" "$out/ap_drive.rawlog" --seed 7 -d 40 \
  -t "$out/ap_drive_truth" -q >/dev/null
"$bin/wifi-calibrate" "$out/ap_drive.rawlog" --array "$share/arrays/rt-ac86u.yaml" \
  --transmitters "$out/ap_drive_truth/transmitters.yaml" --poses "$out/ap_drive_truth/trajectory_tum.txt" \
  --transmit-chains --force --out "$out/calib_aps" -q 2>/dev/null | grep -E "^Transmitter|AoD error|written.*transmitters"
cp -r "$out/calib_aps/transmitters" "$out/calib/"   # the receiver's file stays step 2's
rm -f "$out/ap_drive.rawlog"

echo "== 3. Bearings: csi-bearings (AoA at the robot, AoD at the 4-antenna APs), both sides calibrated"
"$bin/csi-bearings" "$recording" "$out/bearings.rawlog" --algo aod --calib "$out/calib" \
  --tx-array "$share/arrays/ap-linear-4.yaml" --csv "$out/bearings.csv" --images "$out/bearing_images" \
  --image-every 2000 -q

echo "== 4. Kidnapped robot: wifi-pf-localization (MRPT's particle filter + CWiFiBearingMap)"
"$bin/wifi-pf-localization" "$share/localization/pf-localization-wifi.ini" "$out/bearings.rawlog" \
  -g "$out/router/truth/trajectory_tum.txt" -o "$out/pf" -q | tail -12

echo "== 4b. Live: emulator (CSI + odometry on 127.0.0.1) -> wifi-localize --view, 30 s under Xvfb"
live_s=${DEMO_LIVE_SECONDS:-30}
mkdir -p "$out/live"
csi_port=$((20000 + RANDOM % 20000)); odo_port=$((csi_port + 1))
"$bin/rt-ac86u-emulator" --scenario "$share/scenarios/kidnapped.yaml" --preconfigured 155/80 \
  --port "$csi_port" --odometry-port "$odo_port" --state-dir "$out/live/router" \
  --duration $((live_s + 20)) --status-period 0 >"$out/live/emulator.log" 2>&1 &
live_emulator=$!
pids+=("$live_emulator")
sed -e "/^\[WIFI_CSI\]/,/^\[/ s|^udp_port *=.*|udp_port = $csi_port|" \
    -e "/^\[ODOMETRY\]/,/^\[/ s|^udp_port *=.*|udp_port = $odo_port|" \
    -e "s|^bearing_array *=.*|bearing_array = $share/arrays/rt-ac86u.yaml|" \
    -e "s|^bearing_tx_arrays\? *=.*|bearing_tx_arrays = $share/arrays/ap-linear-4.yaml|" \
    -e "s|^transmitters_file *=.*|transmitters_file = $share/localization/kidnapped-aps.yaml|" \
    -e "s|^;* *bearing_calibration *=.*|bearing_calibration = $out/calib|" \
    "$share/localization/wifi-localize-emulator.ini" >"$out/live/live.ini"
xvfb-run -a -s "-screen 0 1280x800x24" "$bin/wifi-localize" -p "$lib/libmrpt_wifi_sensor.so" \
  "$out/live/live.ini" --view --screenshot "$out/live/live_view.png" -d "$live_s" -o "$out/live" -q
kill -TERM "$live_emulator" 2>/dev/null || true; wait "$live_emulator" 2>/dev/null || true
# The live estimate against the truth (same summary as wifi-pf-localization's).
python3 - "$out/live/estimate_tum.txt" "$out/live/router/truth/trajectory_tum.txt" <<'PY'
import bisect, math, statistics, sys
load = lambda f: [list(map(float, l.split())) for l in open(f) if not l.startswith('#')]
est, gt = load(sys.argv[1]), load(sys.argv[2]); gt_t = [g[0] for g in gt]
errs = []
for e in est:
    i = bisect.bisect_left(gt_t, e[0])
    if 0 < i < len(gt):
        a, b = gt[i - 1], gt[i]; w = (e[0] - a[0]) / (b[0] - a[0])
        errs.append((e[0] - est[0][0], math.hypot(e[1] - a[1] - w * (b[1] - a[1]), e[2] - a[2] - w * (b[2] - a[2]))))
after = [v for t, v in errs if t >= 5]
if after:
    print(f"  live estimate: {len(errs)} poses, median error after the first 5 s {statistics.median(after):.2f} m")
PY

echo "== 5. Drift correction: wifi-graphslam on a 5-minute drive with drifting odometry (loop.yaml)"
# The four APs' transmit chains first, from the first 60 s of the same drive (true poses).
# They stand in the corners of a 20 x 12 m hall, 10-14 m from the robot, farther than the 8 m
# wifi-calibrate asks for: it warns, and --force writes them anyway; each file's AoD residual
# (11-15 deg here) widens every AoD sigma, so the graph weighs these bearings accordingly.
"$bin/wifi-sim" "$share/scenarios/loop.yaml" "$out/loop_cal.rawlog" -d 60 -t "$out/loop_cal_truth" -q >/dev/null
"$bin/wifi-calibrate" "$out/loop_cal.rawlog" --array "$share/arrays/rt-ac86u.yaml" \
  --transmitters "$out/loop_cal_truth/transmitters.yaml" --poses "$out/loop_cal_truth/trajectory_tum.txt" \
  --transmit-chains --force --out "$out/calib_loop" -q 2>/dev/null | grep -E "^Transmitter|AoD error"
rm -f "$out/loop_cal.rawlog"
"$bin/wifi-sim" "$share/scenarios/loop.yaml" "$out/loop.rawlog" -d 300 -t "$out/loop_truth" -q >/dev/null
"$bin/csi-bearings" "$out/loop.rawlog" "$out/loop_bearings.rawlog" --algo aod --calib "$out/calib_loop" \
  --tx-array "$share/arrays/ap-linear-2.yaml" -q
rm -f "$out/loop.rawlog"
# AoD only (calibrated transmit chains): loop.yaml turns on the 4366c0's inter-antenna jump
# states, which a fixed receive calibration cannot follow; the APs' own arrays give the angle of
# departure regardless.
"$bin/wifi-graphslam" -r "$out/loop_bearings.rawlog" -a "$share/localization/loop-aps.yaml" --no-aoa \
  -g "$out/loop_truth/trajectory_tum.txt" -o "$out/graphslam" | tail -8

echo "== 6. Device mapping: wifi-iot-map (iot.yaml; receiver calibrated at 2.4 GHz first)"
"$bin/wifi-sim" "$share/scenarios/calibration-2g4.yaml" "$out/cal2g4.rawlog" --seed 5 -d 60 \
  -t "$out/cal2g4_truth" -q >/dev/null
"$bin/wifi-calibrate" "$out/cal2g4.rawlog" --array "$share/arrays/rt-ac86u.yaml" \
  --transmitters "$out/cal2g4_truth/transmitters.yaml" --poses "$out/cal2g4_truth/trajectory_tum.txt" \
  --out "$out/calib" -q
rm -f "$out/cal2g4.rawlog"
"$bin/wifi-sim" "$share/scenarios/iot.yaml" "$out/iot.rawlog" -d 240 -t "$out/iot_truth" -q >/dev/null
"$bin/csi-bearings" "$out/iot.rawlog" "$out/iot_bearings.rawlog" --algo aoa_only --calib "$out/calib" -q
rm -f "$out/iot.rawlog"
# The robot's own trajectory (here the truth, as a localized robot would have it).
"$bin/wifi-iot-map" -r "$out/iot_bearings.rawlog" -t "$out/iot_truth/trajectory_tum.txt" \
  --truth "$out/iot_truth/transmitters.yaml" -o "$out/iot_map" -q | tail -8

echo "== 7. A tcpdump capture (share/samples/, made by the project's encoder) -> rawlog"
"$bin/csi-import" "$share/samples/sample_4x4_80mhz.pcap" "$out/sample.rawlog" -q | tail -3

echo
echo "demo: done. Plots:"
find "$out" -name "*.png" | sort | sed 's/^/  /' | head -40
