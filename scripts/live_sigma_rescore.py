#!/usr/bin/env python3
"""Re-scores the σ of localization-accuracy's live runs as if the smoother's last offset counted.

  python3 scripts/live_sigma_rescore.py SWEEP_WORK [live-odometry|live-no-odometry ...]

For each room-N of a `localization-accuracy -w DIR` folder and each live run (default both),
reads wifi-localize's estimate_cov.csv (reported pose and σ) and pf_estimate_tum.txt (the
particles' mean, one per row) and prints the share of the estimates after convergence inside
their 95 % ellipse two ways:

- as recorded;
- with the rule of 2026-11-28 (LiveLocalizer::uncertainty()): on rows where the smoother gave no
  estimate (reported pose = particles' mean), the squared length of the last offset seen
  (smoothed estimate - particles' mean on the last row that had one) added to σx² and σy².

So a sweep recorded before the rule gives its "after" figure without a new live run. The rows
are output poses, not filter steps: the offset is the last one written, which can be up to one
output period older than the filter's.

The live estimate is on the receiver's clock; the evaluator aligns it with the emulator's
report, which the sweep does not keep. Here the clock offset is the one (in 0.05 s steps, within
5 s of the first rows' difference) that minimises the median error to the true poses, so the
recorded figure can differ from the evaluator's `live_*_inside95_after` column (rooms.csv); it
is printed beside it: trust rooms where the two agree. Convergence as the evaluator's: the
error below 1 m for 5 s.
"""
import bisect
import csv
import math
import os
import re
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pf_rooms import converged_from, read_tum  # noqa: E402

CHI2_2DOF_95 = 5.991


def interpolate(track, t):
    times, xy = track
    i = bisect.bisect_left(times, t)
    if i <= 0 or i >= len(times):
        return None
    a = (t - times[i - 1]) / (times[i] - times[i - 1])
    return (xy[i - 1][0] + a * (xy[i][0] - xy[i - 1][0]),
            xy[i - 1][1] + a * (xy[i][1] - xy[i - 1][1]))


def inside95(sx2, sy2, sxy, dx, dy):
    det = sx2 * sy2 - sxy * sxy
    return det > 0 and (sy2 * dx * dx - 2 * sxy * dx * dy + sx2 * dy * dy) / det <= CHI2_2DOF_95


def rescore(room_dir, run):
    """(poses after convergence, rows without the smoother, inside as recorded, inside with the
    last offset) or None if the run never converged."""
    truth = read_tum(os.path.join(room_dir, "kidnapped", "truth", "trajectory_tum.txt"))
    with open(os.path.join(room_dir, run, "estimate_cov.csv")) as f:
        rows = [[float(x) for x in r] for r in list(csv.reader(f))[1:]]
    pf_mean = read_tum(os.path.join(room_dir, run, "pf_estimate_tum.txt"))[1]
    if not rows:
        return None

    def error_at(row, offset):
        g = interpolate(truth, row[0] - offset)
        return math.hypot(row[1] - g[0], row[2] - g[1]) if g else None

    def median_error(offset):
        e = [x for x in (error_at(r, offset) for r in rows[::10]) if x is not None]
        return statistics.median(e) if e else math.inf

    first = rows[0][0] - truth[0][0]
    offset = min((first + 0.05 * k for k in range(-100, 101)), key=median_error)
    errors = [error_at(r, offset) for r in rows]
    judged = [i for i, e in enumerate(errors) if e is not None]
    start = converged_from([rows[i][0] for i in judged], [errors[i] for i in judged])
    if start is None:
        return None
    converged = judged[start]
    poses = withdrawn = inside = inside_with_offset = 0
    last_offset = None
    for i, r in enumerate(rows):
        smoothed = i < len(pf_mean) and math.hypot(r[1] - pf_mean[i][0], r[2] - pf_mean[i][1]) > 2e-4
        if smoothed:
            last_offset = (r[1] - pf_mean[i][0], r[2] - pf_mean[i][1])
        g = interpolate(truth, r[0] - offset)
        if i < converged or not g:
            continue
        sx2, sy2, sxy = r[4] ** 2, r[5] ** 2, r[6] * r[4] * r[5]
        dx, dy = r[1] - g[0], r[2] - g[1]
        added = 0.0
        if not smoothed and last_offset:
            added = last_offset[0] ** 2 + last_offset[1] ** 2
            withdrawn += 1
        poses += 1
        inside += inside95(sx2, sy2, sxy, dx, dy)
        inside_with_offset += inside95(sx2 + added, sy2 + added, sxy, dx, dy)
    return poses, withdrawn, inside, inside_with_offset


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) > 1 else 2
    work = sys.argv[1]
    runs = sys.argv[2:] or ["live-odometry", "live-no-odometry"]
    evaluator = {}
    if os.path.exists(os.path.join(work, "rooms.csv")):
        with open(os.path.join(work, "rooms.csv")) as f:
            for row in csv.DictReader(f):
                evaluator[row["seed"]] = row
    rooms = sorted((d for d in os.listdir(work) if re.fullmatch(r"room-\d+", d)),
                   key=lambda d: int(d[5:]))
    if not rooms:
        print(f"live_sigma_rescore.py: no room-N folders in {work}", file=sys.stderr)
        return 2
    print("room, run: poses after convergence, without the smoother, inside the 95 % ellipse "
          "(evaluator's figure) as recorded -> with the last offset")
    for room in rooms:
        for run in runs:
            if not os.path.exists(os.path.join(work, room, run, "estimate_cov.csv")):
                continue
            r = rescore(os.path.join(work, room), run)
            if r is None:
                print(f"{room}, {run}: never converged")
                continue
            poses, withdrawn, inside, with_offset = r
            column = "live_odo_inside95_after" if run == "live-odometry" else "live_noodo_inside95_after"
            ev = evaluator.get(room[5:], {}).get(column, "")
            ev = f" ({100 * float(ev):.1f} %)" if ev not in ("", "nan") else ""
            print(f"{room}, {run}: {poses}, {withdrawn} ({100 * withdrawn / poses:.1f} %), "
                  f"{100 * inside / poses:.1f} %{ev} -> {100 * with_offset / poses:.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
