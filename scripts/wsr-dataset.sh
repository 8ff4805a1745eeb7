#!/usr/bin/env bash
# Runs wifi-sar on every sample of WSR Toolbox Dataset sets (github Harvard-REACT/
# WSR-Toolbox-Dataset, 2D-Displacement_raw_data) and prints, per set and displacement source,
# the azimuth errors against the true transmitter positions (as the issue's table compares them
# with WSR's own outputs), how many lie within 3σ, and the receiver located at its start from
# its bearings to the known transmitters (wifi-sar --locate).
#   scripts/wsr-dataset.sh BUILD_DIR DATASET_ROOT OUT_DIR SET [SET...]
# DATASET_ROOT holds Dataset/ and config_files/ (e.g. ../shared/data/wsr). Displacement
# sources: OptiTrack (rx_trajectory), T265 and wheel odometry (each rigidly aligned to
# OptiTrack over the exchanges, so that the bearings are in the frame of the true positions),
# with their position errors given as --position-std (T265 0.02 m, wheel odometry 0.05 m) and
# T265's antenna offset (below). At the end, WSR's own errors for the same locations beside these
# (scripts/wsr_compare.py: its output files, matched to the root's drives by start position).
set -euo pipefail
# The antenna in the T265's body frame: the lever arm that best maps T265 onto OptiTrack, fitted
# on the development sets (LOS_Set_A: -0.222 -0.069, NLOS_Set_C: -0.207 -0.085; their mean), a
# calibration of the robot like a sensor pose, used unchanged on every set.
t265_offset=${WSR_T265_OFFSET:-"-0.215 -0.077"}
build=$(realpath "$1"); root=$(realpath "$2"); out=$3; shift 3
mkdir -p "$out"; out=$(realpath "$out")
for set in "$@"; do
  for src in optitrack t265 odom; do
    csv=$out/$set-$src.csv; rm -f "$csv" "$out/$set-$src.located"
    for loc in "$root"/Dataset/2D-Displacement_raw_data/"$set"/*/; do
      python3 "$(dirname "$0")/wsr_peers.py" "$loc/groundtruth_positions.json" \
        "$root/config_files/dataset.json" > "$out/peers.yaml"
      for rx in "$loc"/csi_rx_*.dat; do
        stamp=$(basename "$rx" .dat); stamp=${stamp#csi_rx_}
        case $src in
          optitrack) traj=(--trajectory "$loc/rx_trajectory_${stamp}_.csv") ;;
          t265) traj=(--trajectory "$loc/t265_rx_trajectory_${stamp}_.csv" --align-to "$loc/rx_trajectory_${stamp}_.csv" --position-std 0.02 --antenna-offset "$t265_offset") ;;
          odom) traj=(--trajectory "$loc/odom_rx_trajectory_${stamp}_.csv" --align-to "$loc/rx_trajectory_${stamp}_.csv" --position-std 0.05) ;;
        esac
        txs=(); for t in "$loc"/csi_tx*_"$stamp".dat; do txs+=(--tx "$t"); done
        "$build/bin/wifi-sar" -q --rx "$rx" "${txs[@]}" "${traj[@]}" --truth "$out/peers.yaml" --locate "$out/peers.yaml" \
          --csv "$out/one.csv" > "$out/one.log" 2>&1 || { echo "$set $stamp $src: failed ($(tail -1 "$out/one.log"))"; continue; }
        if [ -f "$csv" ]; then tail -n +2 "$out/one.csv" >> "$csv"; else cp "$out/one.csv" "$csv"; fi
        { grep -o "located: .* m from" "$out/one.log" || true; } | awk '{print $4}' >> "$out/$set-$src.located"
      done
    done
    [ -f "$csv" ] || continue
    python3 - "$csv" "$set $src" "$out/$set-$src.located" <<'PY'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r['error_deg'] != 'nan']
err = [abs(float(r['error_deg'])) for r in rows]
cov = sum(abs(float(r['error_deg'])) <= 3 * float(r['azimuth_std_deg']) for r in rows)
print('%-22s bearings %3d  |error| mean %5.2f median %5.2f deg  > 30 deg %4.1f %%  within 3 sigma %5.1f %%'
      % (sys.argv[2], len(err), statistics.mean(err), statistics.median(err),
         100 * sum(e > 30 for e in err) / len(err), 100 * cov / len(err)))
import os
loc = [float(x) for x in open(sys.argv[3]).read().split()] if os.path.exists(sys.argv[3]) else []
if loc:
    print('%-22s located from its bearings: %d samples, median %.2f m, p90 %.2f m'
          % ('', len(loc), statistics.median(loc), sorted(loc)[int(0.9 * (len(loc) - 1))]))
PY
  done
done
# WSR's own errors on the same samples (its output files for the locations under the root).
python3 "$(dirname "$0")/wsr_compare.py" "$root" "$@" --ours "$out"
