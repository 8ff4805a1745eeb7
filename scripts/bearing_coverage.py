#!/usr/bin/env python3
"""Receiver-AoA errors and 3-sigma coverage of a localization-accuracy room's kidnapped drive.

  python3 scripts/bearing_coverage.py SWEEP_WORK ROOM [ROOM ...]

Reads SWEEP_WORK/room-N/kidnapped/{bearings.csv, truth/trajectory_tum.txt,
truth/transmitters.yaml}. The true AoA is taken at the nearest true pose, with the random rooms'
receiver 0.1 m ahead of the robot centre (yaw 0); of an ambiguous (linear-array) pair the nearer
member counts. Prints per room: bearings, share within 3 reported sigma (all, and within 75 deg
of broadside), and within 75 deg of broadside the median error and the share beyond 30 deg.
"""
import bisect
import csv
import math
import re
import statistics
import sys


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def read_tum(path):
    poses = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        v = [float(x) for x in line.split()]
        poses.append((v[0], v[1], v[2], 2 * math.atan2(v[6], v[7])))
    return poses


def read_transmitters(path):
    positions, mac = {}, None
    for line in open(path):
        m = re.search(r"mac: '([0-9a-fA-F:]+)'", line)
        if m:
            mac = m.group(1).lower()
        m = re.search(r"position: \[([-0-9.]+), ([-0-9.]+)", line)
        if m and mac:
            positions[mac] = (float(m.group(1)), float(m.group(2)))
    return positions


def room_figures(work, room, sensor_x=0.1):
    d = f"{work}/room-{room}/kidnapped"
    aps = read_transmitters(d + "/truth/transmitters.yaml")
    truth = read_tum(d + "/truth/trajectory_tum.txt")
    times = [p[0] for p in truth]
    n = covered = central = central_covered = 0
    central_errors = []
    for r in csv.DictReader(open(d + "/bearings.csv")):
        t = float(r["timestamp"])
        i = bisect.bisect_left(times, t)
        if i <= 0 or i >= len(truth) or not r["aoa_deg"]:
            continue
        _, x, y, phi = min(truth[i - 1], truth[i], key=lambda p: abs(p[0] - t))
        sx, sy = x + sensor_x * math.cos(phi), y + sensor_x * math.sin(phi)
        ax, ay = aps[r["transmitter"].lower()]
        true = wrap(math.atan2(ay - sy, ax - sx) - phi)
        err = abs(wrap(true - math.radians(float(r["aoa_deg"]))))
        if r["aoa_ambiguous"] == "1" and r["aoa_mirror_deg"]:
            err = min(err, abs(wrap(true - math.radians(float(r["aoa_mirror_deg"])))))
        inside = err <= 3 * math.radians(float(r["aoa_std_deg"]))
        n += 1
        covered += inside
        if min(abs(true), math.pi - abs(true)) <= math.radians(75):
            central += 1
            central_covered += inside
            central_errors.append(math.degrees(err))
    return n, covered, central, central_covered, central_errors


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    for room in sys.argv[2:]:
        n, covered, central, central_covered, errors = room_figures(sys.argv[1], room)
        if not n or not central:
            print(f"room {room}: no bearings matched the true poses")
            continue
        print(f"room {room}: {n} bearings, within 3 sigma {100 * covered / n:.1f} % (within 75 deg "
              f"of broadside {100 * central_covered / central:.1f} %), median error "
              f"{statistics.median(errors):.2f} deg, beyond 30 deg "
              f"{100 * sum(e > 30 for e in errors) / len(errors):.1f} %")


if __name__ == "__main__":
    main()
