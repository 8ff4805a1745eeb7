#!/usr/bin/env python3
"""Phase calibration files against the simulator's truth.

Usage: calibration_vs_truth.py TRUTH_DIR/impairments.json CALIB_DIR

For every channel of the simulated receiver, the file CALIB_DIR/<array>/ch<C>_<BW>mhz.yaml that
wifi-calibrate wrote is compared with the true phase of each chain relative to chain 0 on every
subcarrier the file lists: RMS of the wrapped difference [deg], one line per channel. Exits 1
when a channel has no file.
"""
import glob
import json
import math
import sys

import yaml


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    truth = json.load(open(sys.argv[1]))
    hardware = truth["hardware"]
    hardware = hardware[0] if isinstance(hardware, list) else hardware
    missing = 0
    for channel in hardware["channels"]:
        chanspec = channel["chanspec"]
        centre, bandwidth = chanspec.split("/")
        files = glob.glob(f"{sys.argv[2]}/*/ch{centre}_{bandwidth}mhz.yaml")
        if not files:
            print(f"{chanspec}: no calibration file under {sys.argv[2]}")
            missing += 1
            continue
        calib = yaml.safe_load(open(files[0]))
        column = {k: i for i, k in enumerate(channel["data_subcarriers"])}
        chains = channel["chains"]
        reference = chains[0]["phase_rad_on_data_subcarriers"]
        squares, n = 0.0, 0
        for a in range(1, len(chains)):
            true_phase = chains[a]["phase_rad_on_data_subcarriers"]
            for j, k in enumerate(calib["subcarriers"]):
                if k not in column:
                    continue
                i = column[k]
                e = wrap(calib["phases_rad"][a][j] - (true_phase[i] - reference[i]))
                squares += e * e
                n += 1
        print(f"{chanspec}: {math.degrees(math.sqrt(squares / n)):.2f} deg RMS over {n} "
              f"(chain, subcarrier) pairs ({files[0]})")
    sys.exit(1 if missing else 0)


if __name__ == "__main__":
    main()
