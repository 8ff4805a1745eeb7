#!/usr/bin/env bash
# Live device mapping on the emulator, with ground truth: the README's "live device map" row.
#
#   bash scripts/measure-live-device-map.sh BUILD_DIR WORK_DIR LAYOUT...
#
# For each LAYOUT (0 = share/scenarios/iot.yaml as it is; N > 0 = its three devices moved to
# random places along the walls, drawn from N): calibrates the receiver at 2.4 GHz from a
# simulated drive (calibration-2g4.yaml, seed 5: the same router boot as iot.yaml), streams the
# scenario from rt-ac86u-emulator in real time (CSI + odometry, loopback only) into
# `wifi-localize` with `map_devices = true` for 90 s, then prints every device's error and
# whether the truth lies inside its 95 % ellipse, and the totals over all layouts.
set -euo pipefail
[ $# -ge 3 ] || { sed -n 2,12p "$0"; exit 1; }
top=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "$1" && pwd)/bin; lib=$(cd "$1" && pwd)/lib; share=$top/share
mkdir -p "$2"; work=$(cd "$2" && pwd); shift 2

for layout in "$@"; do
  d=$work/layout$layout; rm -rf "$d"; mkdir -p "$d"; cd "$d"
  echo "== layout $layout ($d)"
  "$bin/wifi-sim" "$share/scenarios/calibration-2g4.yaml" cal.rawlog --seed 5 -d 60 -t caltruth -q >/dev/null
  "$bin/wifi-calibrate" cal.rawlog --array "$share/arrays/rt-ac86u.yaml" \
    --transmitters caltruth/transmitters.yaml --poses caltruth/trajectory_tum.txt --out calib -q >/dev/null
  # Odometry in the map frame (start_at_origin: false), so the map can be compared with the truth.
  sed -e "s#\.\./arrays/#$share/arrays/#" "$share/scenarios/iot.yaml" |
    awk '{print} /^odometry:/{print "  start_at_origin: false"}' > iot.yaml
  python3 - iot.yaml "$layout" <<'PY'
import random, re, sys
path, layout = sys.argv[1], int(sys.argv[2])
text = open(path).read()
if layout:
    rng = random.Random(layout)
    def along_a_wall(_):
        x, y = rng.choice([(rng.uniform(0.5, 9.5), 4.6), (rng.uniform(0.5, 9.5), 0.4),
                           (0.4, rng.uniform(0.5, 4.5)), (9.6, rng.uniform(0.5, 4.5))])
        return "position: [%.2f, %.2f]" % (x, y)
    text = re.sub(r"position: \[[^\]]*\]", along_a_wall, text)
open(path, "w").write(text)
PY
  "$bin/wifi-sim" iot.yaml /dev/null -q -d 1 -t truth >/dev/null
  sed -e "s#^bearing_algorithm .*#bearing_algorithm = aoa_only\nmap_devices = true\nbearing_calibration = $d/calib#" \
      -e "s#\.\./arrays/#$share/arrays/#" \
      -e "s#^transmitters_file .*#transmitters_file = $share/localization/kidnapped-aps.yaml#" \
      -e "s#^udp_port *= 5500#udp_port = 5600#;s#^udp_port *= 5501#udp_port = 5601#" \
      -e "s#^particles_count .*#particles_count = 500#;s#^KLD_m\(in\|ax\)SampleSize .*#KLD_m\1SampleSize = 500#" \
      "$share/localization/wifi-localize-emulator.ini" > live.ini
  "$bin/rt-ac86u-emulator" --scenario iot.yaml --preconfigured 6/20 --port 5600 --odometry-port 5601 \
    --duration 105 --state-dir "$d/emulator" > emulator.log 2>&1 &
  emulator=$!
  sleep 3
  timeout 200 "$bin/wifi-localize" -p "$lib/libmrpt_wifi_sensor.so" live.ini -o live -d 90 \
    --devices-truth truth/transmitters.yaml > live.log 2>&1 || { tail -20 live.log; kill $emulator; exit 1; }
  wait $emulator || true
done

python3 - "$work" <<'PY'
import csv, glob, math, re, statistics, sys
inside = total = 0
errors = []
for d in sorted(glob.glob(sys.argv[1] + "/layout*")):
    truth = {m: (float(x), float(y)) for m, x, y in re.findall(
        r"mac: '([^']+)'\s*\n\s*position: \[([-0-9.]+), ([-0-9.]+)\]",
        open(d + "/truth/transmitters.yaml").read())}
    for r in csv.DictReader(open(d + "/live/devices.csv")):
        if r["localized"] != "1" or r["mac"] not in truth:
            continue
        ex, ey = float(r["x_m"]) - truth[r["mac"]][0], float(r["y_m"]) - truth[r["mac"]][1]
        a, b, c = float(r["cov_xx"]), float(r["cov_xy"]), float(r["cov_yy"])
        d2 = (c * ex * ex - 2 * b * ex * ey + a * ey * ey) / (a * c - b * b)
        ok = d2 <= 5.991  # chi-square, 2 dof, 95 %
        total += 1; inside += ok; errors.append(math.hypot(ex, ey))
        print("%s %-10s error %.2f m, Mahalanobis^2 %.2f %s" % (
            d.rsplit("/", 1)[1], r["name"], errors[-1], d2, "inside" if ok else "OUTSIDE"))
errors.sort()
print("devices: %d, inside their 95 %% ellipse: %d, median error %.2f m, max %.2f m" % (
    total, inside, statistics.median(errors), errors[-1]))
PY
