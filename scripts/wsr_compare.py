#!/usr/bin/env python3
"""WSR's own azimuth errors on the samples of a WSR Toolbox Dataset root, beside this project's.

    wsr_compare.py DATASET_ROOT SET [SET...] [--ours OUT_DIR]

DATASET_ROOT holds Dataset/2D-Displacement_raw_data/SET/<location>/ and WSR's output files
Dataset/2D-Displacement_output_files/default_configuration/SET_using_{groundtruth,t265}_
displacement.json. WSR's files cover every location of a set; a split root (development or
evaluation locations) holds only some. An output entry belongs to the root when its receiver's
true start position lies within 0.1 m of the first OptiTrack pose of one of the root's drives of
that set (WSR's location ids are not trusted to match the directory names). Printed per set and
displacement (OptiTrack = WSR's "groundtruth", T265): WSR's strongest peak's |azimuth error|
mean / median / beyond 30 deg over all its entries, and over those it accepts itself (profile
variance < 0.9). With --ours (scripts/wsr-dataset.sh's OUT_DIR), this project's figures of the
same set and displacement from OUT_DIR/SET-{optitrack,t265,odom}.csv are printed beside them.
"""
import csv
import glob
import json
import math
import os
import statistics
import sys

MATCH_M = 0.1  # a drive's start and WSR's entry of it agree to millimetres; locations are metres apart
WSR_MAX_VARIANCE = 0.9  # WSR rejects an estimate whose profile variance reaches this


def fail(msg):
    sys.stderr.write('wsr_compare.py: %s\n' % msg)
    sys.exit(1)


def drive_starts(root, set_name):
    """(x, y, location directory) of the first OptiTrack pose of every drive of the set."""
    starts = []
    for path in sorted(glob.glob(os.path.join(
            root, 'Dataset', '2D-Displacement_raw_data', set_name, '*', 'rx_trajectory_*_.csv'))):
        with open(path) as f:
            first = f.readline().split(',')
        try:
            starts.append((float(first[2]), float(first[3]), os.path.basename(os.path.dirname(path))))
        except (IndexError, ValueError):
            fail('%s: line 1: expected "time,?,x,y,..." (WSR trajectory CSV)' % path)
    return starts


def summary(errors):
    if not errors:
        return 'no samples'
    return '%3d  mean %5.2f median %5.2f deg  > 30 deg %4.1f %%' % (
        len(errors), statistics.mean(errors), statistics.median(errors),
        100.0 * sum(e > 30 for e in errors) / len(errors))


def wsr_errors(root, set_name, displacement, starts):
    """|azimuth error| of WSR's strongest peak for the entries of the root's drives: all, and
    those WSR accepts; and the locations they came from."""
    path = os.path.join(root, 'Dataset', '2D-Displacement_output_files', 'default_configuration',
                        '%s_using_%s_displacement.json' % (set_name, displacement))
    if not os.path.exists(path):
        return None
    try:
        entries = json.load(open(path))
    except ValueError as e:
        fail('%s: not JSON (%s)' % (path, e))
    every, accepted, locations = [], [], set()
    for key, sample in entries.items():
        for tx in sample:
            try:
                start = tx['b_INFO_Receiving_robot']['groundtruth_start_position']
                profile = tx['d_INFO_AOA_profile']
                error = abs(float(profile['Top_N_peaks']['1']['azimuth_error']))
                variance = float(profile['Profile_variance'])
            except (KeyError, TypeError, ValueError) as e:
                fail('%s: entry %s: missing or bad field %s' % (path, key, e))
            near = [s for s in starts if math.hypot(s[0] - start['x'], s[1] - start['y']) < MATCH_M]
            if not near:
                continue
            locations.add(near[0][2])
            every.append(error)
            if variance < WSR_MAX_VARIANCE:
                accepted.append(error)
    return every, accepted, locations


def ours(out_dir, set_name, source):
    path = os.path.join(out_dir, '%s-%s.csv' % (set_name, source))
    if not os.path.exists(path):
        return None
    rows = [r for r in csv.DictReader(open(path)) if r['error_deg'] != 'nan']
    errors = [abs(float(r['error_deg'])) for r in rows]
    covered = sum(abs(float(r['error_deg'])) <= 3 * float(r['azimuth_std_deg']) for r in rows)
    text = summary(errors)
    if rows:
        text += '  within 3 sigma %5.1f %%' % (100.0 * covered / len(rows))
    return text


def main(argv):
    out_dir = None
    if '--ours' in argv:
        i = argv.index('--ours')
        if i + 1 >= len(argv):
            fail('--ours needs a directory')
        out_dir = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) < 2 or argv[0] in ('-h', '--help'):
        print(__doc__)
        return 0 if argv and argv[0] in ('-h', '--help') else 1
    root, sets = argv[0], argv[1:]
    for set_name in sets:
        starts = drive_starts(root, set_name)
        if not starts:
            fail("%s: no drives of %s (Dataset/2D-Displacement_raw_data/%s/*/rx_trajectory_*_.csv)"
                 % (root, set_name, set_name))
        for displacement, source in (('groundtruth', 'optitrack'), ('t265', 't265'), (None, 'odom')):
            mine = ours(out_dir, set_name, source) if out_dir else None
            wsr = wsr_errors(root, set_name, displacement, starts) if displacement else None
            if mine is None and wsr is None:
                continue
            label = '%s %s' % (set_name, source)
            if mine is not None:
                print('%-22s ours: bearings %s' % (label, mine))
                label = ''
            if wsr is None:
                print('%-22s WSR:  not reported' % label)
                continue
            every, accepted, locations = wsr
            print('%-22s WSR:  bearings %s  (locations: %s)' % (
                label, summary(every), ' '.join(sorted(l.rsplit('_', 1)[-1] for l in locations))))
            print('%-22s WSR accepted (variance < %.1f): %s' % ('', WSR_MAX_VARIANCE, summary(accepted)))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
