#!/usr/bin/env python3
"""Re-runs the kidnapped-robot filter of localization-accuracy's rooms with .ini changes.

  python3 scripts/pf_rooms.py BUILD_DIR SWEEP_WORK OUT_DIR odometry|none [--seeds 1,2,3]
                              [--rooms 1,2] [--jobs 2] [--aps N] [--skip S] [--live-steps N]
                              [Section/key=value ...]

SWEEP_WORK is a `localization-accuracy -w DIR` folder (its room-N/pf.ini and the recorded
kidnapped/ bearings, odometry and true poses). Each room and filter seed runs
wifi-pf-localization offline, 3000 particles, with the room's pf.ini changed as given; the
figure is the sweep's: median error of the estimate (estimate_tum.txt: the PF mean refined by the
window smoother) against the true poses after convergence
(error < 1 m for 5 s; never: infinite). Prints each room's runs and median, then the runs within
0.3 m, the runs that never converged and the rooms whose median is within 0.3 m.

--aps N keeps only the room's first N access points (their bearings and map entries): on a sweep
run with `localization-accuracy --aps 4` it gives the same rooms and drives with the seed's three
APs, since the APs beyond the third come from a stream of their own.

Without odometry (`none`) the bearings are kidnapped/bearings-no-odometry.csv, as the evaluator
uses them: csi-bearings with the rawlog's odometry ignored (a robot without odometry has none for
its bearing windows either). Sweeps made before the evaluator wrote that file get it here, once:
the room's drive simulated again (wifi-sim is deterministic) and estimated with --no-odometry.
--odometry-bearings takes kidnapped/bearings.csv instead (windows chosen with the odometry: how
sweeps before 2026-11-27 ran without odometry).

--skip S starts the filter S seconds into the drive (the bearings before it dropped, both
programs' --skip), as a live run that came up late. --live-steps N (without odometry) runs
wifi-localize's filter instead, live-replay on the same bearings, N queued at a time, with the
room's live-no-odometry.ini (a sweep run with its live runs): a live run without the clock. The
.ini's [wifi-localize] max_bearings_per_step splits each N further, as live (sweeps before
2026-11-28: 0, one step of N; give wifi-localize/max_bearings_per_step=2 for today's).
"""
import argparse
import bisect
import concurrent.futures
import math
import os
import re
import shutil
import statistics
import subprocess
import sys


def derive_ini(src, dst, overrides, drop=()):
    """Copy of src with [Section] key = value set (replaced, or added to its section), and
    without the sections named in drop."""
    wanted = {}
    for o in overrides:
        key, value = o.split("=", 1)
        section, name = key.split("/", 1)
        if section not in drop:
            wanted.setdefault(section, {})[name] = value
    out, done, section = [], set(), None

    def flush(sec):
        for name, value in wanted.get(sec, {}).items():
            if (sec, name) not in done:
                out.append(f"{name} = {value}")
                done.add((sec, name))

    for line in open(src).read().splitlines():
        m = re.match(r"\s*\[(.+)\]", line)
        if m:
            flush(section)
            section = m.group(1)
        if section in drop:
            continue
        if not m:
            m = re.match(r"\s*([^;=\s]+)\s*=", line)
            if m and m.group(1) in wanted.get(section, {}):
                line = f"{m.group(1)} = {wanted[section][m.group(1)]}"
                done.add((section, m.group(1)))
        out.append(line)
    flush(section)
    for sec in wanted:
        if not any((sec, n) in done for n in wanted[sec]):
            out.append(f"[{sec}]")
            flush(sec)
    open(dst, "w").write("\n".join(out) + "\n")


def keep_first_aps(truth_dir, bearings_csv, count, out):
    """The room's transmitters.yaml and bearings.csv with only its first `count` APs, in out."""
    text = open(os.path.join(truth_dir, "transmitters.yaml")).read()
    head, *blocks = re.split(r"(?m)^(?=  - name:)", text)
    if len(blocks) < count:
        raise ValueError(f"{truth_dir}: {len(blocks)} APs, fewer than --aps {count}")
    kept = blocks[:count]
    macs = {re.search(r"mac: '([^']+)'", b).group(1).lower() for b in kept}
    aps = os.path.join(out, "transmitters.yaml")
    open(aps, "w").write(head + "".join(kept))
    csv = os.path.join(out, "bearings.csv")
    with open(bearings_csv) as src, open(csv, "w") as f:
        for line in src:
            fields = line.split(",")
            if line.startswith(("#", "timestamp")) or (
                    len(fields) > 1 and fields[1].lower() in macs):
                f.write(line)
    return aps, csv


def no_odometry_bearings(build, room_dir):
    """kidnapped/bearings-no-odometry.csv of a sweep's room, estimated from its drive if missing
    (with the AP arrays when its bearings carry AoD, as the evaluator's --aod)."""
    kidnapped = os.path.join(room_dir, "kidnapped")
    csv = os.path.join(kidnapped, "bearings-no-odometry.csv")
    if os.path.exists(csv):
        return csv
    with open(os.path.join(kidnapped, "bearings.csv")) as f:
        header = f.readline().strip().split(",")
        aod = any(row.split(",")[header.index("has_aod")] == "1" for row in f)
    with open(os.path.join(kidnapped, "scenario.yaml")) as f:
        streams = re.findall(r"streams: (\d+)", f.read())
    rawlog = os.path.join(kidnapped, "drive-no-odometry.rawlog")
    truth = os.path.join(kidnapped, "truth-again")
    share = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "share", "arrays")
    try:
        subprocess.run([os.path.join(build, "bin", "wifi-sim"), os.path.join(kidnapped, "scenario.yaml"),
                        rawlog, "-q", "-t", truth], check=True, capture_output=True)
        cmd = [os.path.join(build, "bin", "csi-bearings"), rawlog, "/dev/null", "--no-odometry",
               "--calib", os.path.join(room_dir, "calib"), "--csv", csv + ".tmp", "-q"]
        if aod:
            cmd += ["--tx-array", os.path.join(share, f"ap-linear-{max(map(int, streams))}.yaml")]
        subprocess.run(cmd, check=True, capture_output=True)
        os.replace(csv + ".tmp", csv)
    finally:
        for leftover in (rawlog, csv + ".tmp"):
            if os.path.exists(leftover):
                os.remove(leftover)
        shutil.rmtree(truth, ignore_errors=True)
    return csv


def read_tum(path):
    times, xy = [], []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        v = [float(x) for x in line.split()]
        times.append(v[0])
        xy.append((v[1], v[2]))
    return times, xy


def median_after_convergence(estimate, truth, threshold_m=1.0, hold_s=5.0):
    tt, txy = truth
    times, errors = [], []
    for t, (x, y) in zip(*estimate):
        i = bisect.bisect_left(tt, t)
        if i <= 0 or i >= len(tt):
            continue
        a = (t - tt[i - 1]) / (tt[i] - tt[i - 1])
        gx = txy[i - 1][0] + a * (txy[i][0] - txy[i - 1][0])
        gy = txy[i - 1][1] + a * (txy[i][1] - txy[i - 1][1])
        times.append(t)
        errors.append(math.hypot(x - gx, y - gy))
    start = converged_from(times, errors, threshold_m, hold_s)
    return math.inf if start is None else statistics.median(errors[start:])


def converged_from(times, errors, threshold_m=1.0, hold_s=5.0):
    """Index from which the error stays below threshold_m for hold_s (the evaluator's
    convergence), or None if it never does."""
    run = 0
    for i, e in enumerate(errors):
        if e >= threshold_m:
            run = i + 1
        elif times[i] - times[run] >= hold_s:
            return run
    return None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("build")
    p.add_argument("work")
    p.add_argument("out")
    p.add_argument("motion", choices=["odometry", "none"])
    p.add_argument("--seeds", default="1,2,3")
    p.add_argument("--rooms", default="")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--aps", type=int, default=0, help="keep the first N access points only")
    p.add_argument("--odometry-bearings", action="store_true",
                   help="without odometry, the bearings estimated with it (kidnapped/bearings.csv)")
    p.add_argument("--skip", type=float, default=0.0,
                   help="start the filter this many seconds into the drive")
    p.add_argument("--live-steps", type=int, default=0,
                   help="wifi-localize's filter (live-replay), N bearings queued at a time")
    p.add_argument("overrides", nargs="*", help="Section/key=value")
    a = p.parse_intermixed_args()
    if a.live_steps and a.motion != "none":
        print("pf_rooms.py: --live-steps runs without odometry only (motion: none)", file=sys.stderr)
        return 2
    if a.live_steps < 0 or a.skip < 0:
        print("pf_rooms.py: --live-steps and --skip must be >= 0", file=sys.stderr)
        return 2
    program = os.path.join(a.build, "bin", "live-replay" if a.live_steps else "wifi-pf-localization")
    if not os.access(program, os.X_OK):
        print(f"pf_rooms.py: {program}: not found (build first)", file=sys.stderr)
        return 2
    if not os.path.isdir(a.work):
        print(f"pf_rooms.py: {a.work}: not a folder (a localization-accuracy -w DIR)", file=sys.stderr)
        return 2
    rooms = sorted((d for d in os.listdir(a.work) if re.fullmatch(r"room-\d+", d)),
                   key=lambda d: int(d[5:]))
    if a.rooms:
        rooms = [r for r in rooms if r[5:] in a.rooms.split(",")]
    if not rooms:
        print(f"pf_rooms.py: no room-N folders in {a.work}"
              + (f" among --rooms {a.rooms}" if a.rooms else ""), file=sys.stderr)
        return 2
    seeds = [int(s) for s in a.seeds.split(",")]
    os.makedirs(a.out, exist_ok=True)

    def run(room, seed):
        src = os.path.join(a.work, room)
        out = os.path.join(a.out, f"{room}-seed{seed}")
        os.makedirs(out, exist_ok=True)
        ini = os.path.join(out, "pf.ini")
        derive_ini(os.path.join(src, "pf.ini"), ini, a.overrides)
        truth = os.path.join(src, "kidnapped", "truth")
        aps = os.path.join(truth, "transmitters.yaml")
        bearings = os.path.join(src, "kidnapped", "bearings.csv")
        if a.motion == "none" and not a.odometry_bearings:
            bearings = os.path.join(src, "kidnapped", "bearings-no-odometry.csv")
        if a.aps:
            aps, bearings = keep_first_aps(truth, bearings, a.aps, out)
        if a.live_steps:
            live_ini = os.path.join(src, "live-no-odometry.ini")
            if not os.path.exists(live_ini):
                return room, seed, None, [f"{live_ini}: not found (a sweep run with --no-live?)"]
            ini = os.path.join(out, "live.ini")
            derive_ini(live_ini, ini, a.overrides)
            cmd = [program, ini, "-q", "--bearings-per-step", str(a.live_steps)]
        else:
            cmd = [program, ini, "-q", "--no-plots"]
        cmd += ["--seed", str(seed), "-n", "3000", "-m", aps, "-b", bearings, "--skip", str(a.skip),
                "--sensor-pose", "0.1", "0", "0.4", "0", "0", "0", "-o", out]
        if a.motion == "odometry":
            cmd += ["--odometry-tum", os.path.join(truth, "odometry_tum.txt")]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode:
            return room, seed, None, r.stderr.strip().splitlines()[-1:]
        return room, seed, median_after_convergence(
            read_tum(os.path.join(out, "estimate_tum.txt")),
            read_tum(os.path.join(truth, "trajectory_tum.txt"))), None

    if a.motion == "none" and not a.odometry_bearings:
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
            try:
                list(ex.map(lambda r: no_odometry_bearings(a.build, os.path.join(a.work, r)), rooms))
            except subprocess.CalledProcessError as e:
                print(f"pf_rooms.py: estimating the bearings without odometry: {e.cmd[0]} failed: "
                      f"{e.stderr.decode().strip().splitlines()[-1:]}", file=sys.stderr)
                return 1
    results, failed = {}, 0
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        for room, seed, m, err in ex.map(lambda rs: run(*rs), [(r, s) for r in rooms for s in seeds]):
            if m is None:
                print(f"{room} seed {seed}: {os.path.basename(program)} failed: {err}", file=sys.stderr)
                failed += 1
                continue
            results.setdefault(room, []).append(m)
    fmt = lambda v: "never" if math.isinf(v) else f"{v:.2f}"
    good = never = good_rooms = 0
    for room in rooms:
        runs = results.get(room, [])
        if not runs:
            continue
        med = statistics.median(runs)
        good += sum(v <= 0.3 for v in runs)
        never += sum(math.isinf(v) for v in runs)
        good_rooms += med <= 0.3
        print(f"{room}: {' '.join(fmt(v) for v in runs)}  median {fmt(med)} m")
    n = sum(len(v) for v in results.values())
    print(f"runs within 0.3 m: {good} / {n}, never converged: {never}, "
          f"rooms with median within 0.3 m: {good_rooms} / {len(results)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
