#!/usr/bin/env bash
# Drift correction and device mapping again on the rooms of a localization-accuracy sweep
# (issue 19.3), without re-simulating: the sweep keeps each room's loop bearings, odometry and
# truth under WORK/room-N/loop/. Runs the commands the evaluator runs:
#   wifi-graphslam --aps (known APs), wifi-graphslam --estimate-aps, and
#   wifi-iot-map --odometry-tum (the APs as devices, odometry anchored at the true start)
# and prints one line per room: median ATE reduction vs odometry (known / estimated APs), the
# devices' median error and how many lie inside their 95 % ellipse.
#   scripts/loop-rooms.sh BUILD_DIR SWEEP_WORK_DIR OUT_DIR
set -euo pipefail
build=$(realpath "$1"); sweep=$(realpath "$2"); out=$3; shift 3
mkdir -p "$out"; out=$(realpath "$out")
pose="--sensor-pose 0.1 0 0.4 0 0 0"  # the random rooms' receiver (localization_accuracy.cpp)
median() { sort -g | awk '{v[NR]=$1} END {if (NR == 0) print "nan"; else if (NR % 2) print v[(NR+1)/2]; else print (v[NR/2]+v[NR/2+1])/2}'; }
printf "%-10s %-24s %-24s %s\n" room "drift red. known" "drift red. estimated" "devices"
for dir in $(ls -d "$sweep"/room-* | sort -V); do
  room=$(basename "$dir"); lt=$dir/loop/truth; o=$out/$room; mkdir -p "$o"
  [ -f "$lt/odometry_tum.txt" ] || { echo "$room: no loop recorded" >&2; continue; }
  # The odometry's first pose at the true start: x y yaw of the truth's first row.
  start=$(awk '!/^#/ {printf "%s %s %.3f", $2, $3, 2 * atan2($7, $8) * 180 / 3.14159265358979; exit}' \
    "$lt/trajectory_tum.txt")
  line=""
  for est in known estimated; do
    extra=""; [ $est = estimated ] && extra="--estimate-aps --true-aps $lt/transmitters.yaml"
    nice "$build/bin/wifi-graphslam" -b "$dir/loop/bearings.csv" --odometry-tum "$lt/odometry_tum.txt" \
      --aps "$lt/transmitters.yaml" $extra $pose -g "$lt/trajectory_tum.txt" -o "$o/slam-$est" \
      --no-plots > "$o/slam-$est.log" 2>&1 || { line+=$(printf "%-24s " failed); continue; }
    odo=$(grep -m1 "ATE odometry only" "$o/slam-$est.log" | sed 's/.*median=\([0-9.]*\).*/\1/')
    slam=$(grep -m1 "ATE WiFi graph SLAM" "$o/slam-$est.log" | sed 's/.*median=\([0-9.]*\).*/\1/')
    line+=$(awk -v a="$slam" -v b="$odo" 'BEGIN {printf "%-24s ", sprintf("%.0f %% (%.3f m)", 100 * (1 - a / b), a)}')
  done
  nice "$build/bin/wifi-iot-map" -b "$dir/loop/bearings.csv" --odometry-tum "$lt/odometry_tum.txt" \
    --initial-pose "$start" $pose --truth "$lt/transmitters.yaml" -q --no-plots -o "$o/devices" \
    > "$o/devices.log" 2>&1 || { echo "$room: wifi-iot-map failed ($o/devices.log)"; continue; }
  med=$(grep -o "error=[0-9.]*" "$o/devices.log" | cut -d= -f2 | median)
  inside=$(grep -o "inside their 95 % ellipse: [0-9]* of [0-9]*" "$o/devices.log" | sed 's/.*: //')
  printf "%-10s %s median %s m, %s inside their 95 %% ellipse\n" "$room" "$line" "$med" "$inside"
done
