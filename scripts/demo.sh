#!/usr/bin/env bash
# The end-to-end demo: installs what is needed, builds, then runs the whole story on the
# emulated router, with no hardware:
#   1. an emulated RT-AC86U (simulated robot among 4 access points) sends Nexmon CSI to
#      127.0.0.1, and is configured over ssh (a throw-away sshd on 127.0.0.1) by Debian's
#      rawlog-grabber loading the CWiFiCSISensor plugin, which records a rawlog;
#   2. Debian's rawlog-edit reads that rawlog through the observation plugin;
#   3. a capture file (pcap) from the project's encoder becomes a rawlog (csi-pcap2rawlog).
# Outputs go to demo-output/ (or $DEMO_OUT).
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

echo "== 1. Emulated RT-AC86U + sshd on 127.0.0.1 + rawlog-grabber"
port=$((20000 + RANDOM % 20000))
"$bin/rt-ac86u-emulator" --scenario "$share/scenarios/kidnapped.yaml" --port "$port" --dest 127.0.0.1 \
  --state-dir "$out/router" --duration 120 --status-period 0 >"$out/emulator.log" 2>&1 &
pids+=($!)
sleep 1
source scripts/loopback-sshd.sh
start_loopback_sshd "$out/sshd" "$out/router/bin"   # sets SSHD_PORT, SSHD_KEY, SSHD_KNOWN_HOSTS
pids+=("$SSHD_PID")

sed -e "s|^login_host *=.*|login_host = 127.0.0.1|" -e "s|^login_port *=.*|login_port = $SSHD_PORT|" \
    -e "s|^login_user *=.*|login_user = $(id -un)|" -e "s|^login_identity_file *=.*|login_identity_file = $SSHD_KEY|" \
    -e "s|^login_known_hosts *=.*|login_known_hosts = $SSHD_KNOWN_HOSTS|" \
    -e "s|^udp_port *=.*|udp_port = $port|" -e "s|^udp_bind_address *=.*|udp_bind_address = 127.0.0.1|" \
    -e "s|^router_address *=.*|router_address = 127.0.0.1|" -e "s|^channel *=.*|channel = 155/80|" \
    -e "s|^rawlog_prefix *=.*|rawlog_prefix = recording|" -e "s|^status_period *=.*|status_period = 2|" \
    "$share/rawlog-grabber/csi_receiver.ini" >"$out/grab.ini"
(cd "$out" && (sleep 8; echo) | rawlog-grabber -p "$lib/libmrpt_wifi_sensor.so" grab.ini >grabber.log 2>&1)
grep -E "CWiFiCSISensor" "$out/grabber.log" | cut -c1-220 | tail -6
recording=$(ls "$out"/recording_*.rawlog)

echo "== 2. Debian's rawlog-edit reads the recording through the plugin"
rawlog-edit -p "$lib/libmrpt_wifi_obs.so" --info -i "$recording" | grep -E "objects|labels|Sensor"
"$bin/csi-export" "$recording" --stats -q

echo "== 3. A tcpdump capture (share/samples/, made by the project's encoder) -> rawlog"
"$bin/csi-pcap2rawlog" "$share/samples/sample_4x4_80mhz.pcap" "$out/sample.rawlog" -q
rawlog-edit -p "$lib/libmrpt_wifi_obs.so" --describe --to-index 0 -i "$out/sample.rawlog" 2>/dev/null |
  sed -n '/WiFi CSI/,/^---/p' | head -30

echo "demo: done; outputs in $out"
