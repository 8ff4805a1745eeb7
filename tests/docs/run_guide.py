#!/usr/bin/env python3
"""Runs a guide's command blocks against the RT-AC86U emulator, from a build tree.

The convention of the guides (docs/robot-guide.md, docs/rt-ac86u.md):
  ```bash   run, in order, each in its own `bash -euo pipefail`; the working folder carries over
            from one block to the next (a `cd` in one block holds for the following ones)
  ```ini    whose first line is `; FILE.ini [FILE2.ini ...]`: set these keys, in these sections,
            in those files of the working folder; every key must already be in its section
  ```sh     shown, not run (needs the real router)
  ```text   output, not run
  <NAME>    a value the user fills in: replaced by the emulator's value (PLACEHOLDERS below); a
            placeholder the test does not know fails the test
  /usr/local/bin, /usr/local/lib/, /usr/local/share/mrpt_wifi: replaced by the build tree's
            bin/ and lib/ and the source tree's share/ (the guide is written for an install)

What differs between the emulator and a stock router, and so is set by this test (not by the
guide) in every .ini of the working folder before each block: the ssh port and known_hosts of a
throw-away sshd on 127.0.0.1, the UDP ports, the CSI's source address (127.0.0.1, not Nexmon's
10.10.10.10) and the bind address (loopback only).

The emulator plays share/scenarios/kidnapped.yaml with its APs sending --frame-rate frames per
second (default 10, a real AP's beacon rate; the scenario's 100 would only make every step
slower). ctest runs the robot guide at 20 (beacons and some traffic) with a 20 s drive: the 300+
frames per AP that the calibration needs, in about 70 s instead of 113 s. The test fails
when a block exits non-zero, a file the guide names (share/..., /usr/local/share/mrpt_wifi/...,
or an output such as `pf/estimate_tum.txt`) is missing, or a placeholder is unknown.

Usage: run_guide.py --source SRC --build BUILD [--guide docs/robot-guide.md] [--keep DIR]
       [--drive-seconds 40] [--check-seconds 20] [--live-seconds 30] [--frame-rate 10]
"""
import argparse
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

BLOCK_TIMEOUT_S = 600


def fail(msg):
    print("FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def parse_blocks(path):
    """[(lang, text, first_line_number)] of the fenced blocks of a Markdown file."""
    blocks, lang, buf, start = [], None, [], 0
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            m = re.match(r"^```(\w*)\s*$", line)
            if m and lang is None:
                lang, buf, start = m.group(1), [], n + 1
            elif line.startswith("```") and lang is not None:
                blocks.append((lang, "".join(buf), start))
                lang = None
            elif lang is not None:
                buf.append(line)
    if lang is not None:
        fail(f"{path}: a ``` block opened at line {start - 1} is never closed")
    return blocks


def free_udp_port_pair():
    """Two consecutive free UDP ports on 127.0.0.1 (CSI, odometry)."""
    for _ in range(100):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port >= 65535:
            continue
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s2:
                s2.bind(("127.0.0.1", port + 1))
            return port, port + 1
        except OSError:
            continue
    fail("no two consecutive free UDP ports on 127.0.0.1")


def set_ini_keys(path, section, values, must_exist, origin):
    """Sets key = value in [section] of an .ini file, keeping its comments."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    current, seen_section = None, False
    done = set()
    for i, line in enumerate(lines):
        m = re.match(r"^\s*\[([^\]]+)\]", line)
        if m:
            current = m.group(1).strip()
            seen_section |= current == section
            continue
        if current != section:
            continue
        m = re.match(r"^(\s*)([A-Za-z0-9_]+)(\s*=).*$", line)
        if m and m.group(2) in values and m.group(2) not in done:
            lines[i] = f"{m.group(1)}{m.group(2)}{m.group(3)} {values[m.group(2)]}"
            done.add(m.group(2))
    missing = [k for k in values if k not in done]
    if must_exist and (not seen_section or missing):
        what = f"section [{section}]" if not seen_section else f"key(s) {', '.join(missing)} in [{section}]"
        fail(f"{origin}: sets {what} of {os.path.basename(path)}, which the file does not have")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def apply_ini_block(text, cwd, substitute, origin):
    lines = [l for l in substitute(text, origin).split("\n")]
    m = re.match(r"^;\s*(.+)$", lines[0]) if lines else None
    if not m or not all(w.endswith(".ini") for w in m.group(1).split()):
        return  # an .ini excerpt for reading, not values to set
    files = m.group(1).split()
    section, values = None, {}
    per_section = []
    for line in lines[1:]:
        line = line.strip()
        if not line or line.startswith(";") or line.startswith("#"):
            continue
        s = re.match(r"^\[([^\]]+)\]$", line)
        if s:
            if section and values:
                per_section.append((section, values))
            section, values = s.group(1), {}
            continue
        kv = re.match(r"^([A-Za-z0-9_]+)\s*=\s*(.*)$", line)
        if not kv or section is None:
            fail(f"{origin}: cannot read '{line}' (key = value under a [section])")
        values[kv.group(1)] = kv.group(2)
    if section and values:
        per_section.append((section, values))
    for name in files:
        path = os.path.join(cwd, name)
        if not os.path.isfile(path):
            fail(f"{origin}: names {name}, which is not in the working folder {cwd}")
        for sec, vals in per_section:
            set_ini_keys(path, sec, vals, True, origin)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--guide", default="docs/robot-guide.md")
    ap.add_argument("--keep", help="work in this folder and keep it (default: a temporary one)")
    ap.add_argument("--drive-seconds", type=int, default=40)
    ap.add_argument("--check-seconds", type=int, default=20)
    ap.add_argument("--live-seconds", type=int, default=30)
    ap.add_argument("--frame-rate", type=int, default=10)
    args = ap.parse_args()

    src = os.path.abspath(args.source)
    build = os.path.abspath(args.build)
    guide = os.path.join(src, args.guide)
    bindir, libdir, share = os.path.join(build, "bin"), os.path.join(build, "lib"), os.path.join(src, "share")
    for tool in ("rt-ac86u-emulator", "rt-ac86u-shim"):
        if not os.access(os.path.join(bindir, tool), os.X_OK):
            fail(f"{tool} is not built in {bindir}")
    if not os.access("/usr/sbin/sshd", os.X_OK):
        fail("/usr/sbin/sshd is missing (Debian package openssh-server)")

    work = os.path.abspath(args.keep) if args.keep else tempfile.mkdtemp(prefix="mrpt_wifi_guide_")
    if args.keep:
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
    blocks = parse_blocks(guide)
    if not any(lang == "bash" for lang, _, _ in blocks):
        fail(f"{guide}: no ```bash block to run")

    # The emulated router: kidnapped.yaml with beacon-rate APs, arrays by absolute path.
    with open(os.path.join(share, "scenarios", "kidnapped.yaml"), encoding="utf-8") as f:
        scenario = f.read()
    scenario = scenario.replace("frame_rate_hz: 100", "frame_rate_hz: " + str(args.frame_rate))
    scenario = scenario.replace("../arrays/", os.path.join(share, "arrays") + "/")
    with open(os.path.join(work, "scenario.yaml"), "w", encoding="utf-8") as f:
        f.write(scenario)
    csi_port, odo_port = free_udp_port_pair()
    procs = []
    sshd_pid = None
    try:
        emulator = subprocess.Popen(
            [os.path.join(bindir, "rt-ac86u-emulator"), "--scenario", os.path.join(work, "scenario.yaml"),
             "--port", str(csi_port), "--odometry-port", str(odo_port), "--dest", "127.0.0.1",
             "--state-dir", os.path.join(work, "router"), "--truth-dir", os.path.join(work, "truth"),
             "--duration", "1200", "--status-period", "0"],
            stdout=open(os.path.join(work, "emulator.log"), "w"), stderr=subprocess.STDOUT)
        procs.append(emulator)
        for _ in range(100):
            if os.path.exists(os.path.join(work, "router", "emulator.sock")):
                break
            if emulator.poll() is not None:
                fail("the emulator exited: " + open(os.path.join(work, "emulator.log")).read())
            time.sleep(0.1)
        # The throw-away sshd of scripts/loopback-sshd.sh, remote PATH = the emulator's tools.
        # (Files, not pipes: the sshd left running keeps the shell's descriptors open.)
        sshd_out = os.path.join(work, "sshd.vars")
        with open(sshd_out, "w") as o, open(os.path.join(work, "sshd.start.log"), "w") as e:
            r = subprocess.run(
                ["bash", "-c", 'source "$1"; start_loopback_sshd "$2" "$3" || exit 1; '
                 'echo "$SSHD_PORT $SSHD_KEY $SSHD_KNOWN_HOSTS $SSHD_PID"', "bash",
                 os.path.join(src, "scripts", "loopback-sshd.sh"), os.path.join(work, "sshd"),
                 os.path.join(work, "router", "bin")],
                stdin=subprocess.DEVNULL, stdout=o, stderr=e, timeout=60)
        if r.returncode != 0:
            fail("loopback sshd: " + open(os.path.join(work, "sshd.start.log")).read())
        sshd_port, sshd_key, sshd_known_hosts, sshd_pid = open(sshd_out).read().split()
        sshd_pid = int(sshd_pid)

        with open(os.path.join(share, "scenarios", "kidnapped.yaml"), encoding="utf-8") as f:
            macs = ",".join(re.findall(r"mac: '([0-9a-f:]+)'", f.read()))
        placeholders = {
            "ROUTER_LAN_IP": "127.0.0.1",
            "ROUTER_USER": subprocess.run(["id", "-un"], capture_output=True, text=True).stdout.strip(),
            "ROUTER_KEY": sshd_key,
            "CHANNEL": "155/80",
            "AP_MACS": macs,
            # kidnapped.yaml's receiver: sensor_pose {x: 0.1, y: 0.0, z: 0.4, yaw_deg: 0}
            "POSE_X": "0.10", "POSE_Y": "0", "POSE_Z": "0.40", "POSE_YAW": "0",
            # its room, 10 x 5 m
            "X_MIN": "0", "X_MAX": "10", "Y_MIN": "0", "Y_MAX": "5",
            # motion start [5.0, 2.5, 0]: the emulator's odometry starts there
            "START_POSE": "5 2.5 0",
            # ap-ne
            "CALIB_AP_MAC": "02:00:00:00:01:02", "CALIB_AP_XY": "9.7 4.7",
            "DRIVE_SECONDS": str(args.drive_seconds),
            "CHECK_SECONDS": str(args.check_seconds),
            "LIVE_SECONDS": str(args.live_seconds),
        }
        overrides = {
            "WIFI_CSI": {"login_port": sshd_port, "login_known_hosts": sshd_known_hosts,
                         "udp_port": str(csi_port), "udp_bind_address": "127.0.0.1",
                         "router_address": "127.0.0.1"},
            "ODOMETRY": {"udp_port": str(odo_port), "udp_bind_address": "127.0.0.1"},
        }

        def substitute(text, origin):
            text = text.replace("/usr/local/lib/", libdir + "/")
            text = text.replace("/usr/local/share/mrpt_wifi", share)
            text = text.replace("/usr/local/bin/", bindir + "/")

            def repl(m):
                if m.group(1) not in placeholders:
                    fail(f"{origin}: unknown placeholder <{m.group(1)}>")
                return placeholders[m.group(1)]
            return re.sub(r"<([A-Z][A-Z0-9_]*)>", repl, text)

        def apply_overrides(cwd):
            for name in os.listdir(cwd):
                path = os.path.join(cwd, name)
                if not (name.endswith(".ini") and os.path.isfile(path)):
                    continue
                with open(path, encoding="utf-8") as f:
                    sections = set(re.findall(r"^\s*\[([^\]]+)\]", f.read(), re.M))
                for sec, vals in overrides.items():
                    if sec in sections:
                        set_ini_keys(path, sec, vals, False, "test override")

        env = dict(os.environ)
        env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
        cwd = os.path.join(work, "user")
        os.makedirs(cwd)
        cwd_file = os.path.join(work, "cwd")
        rel = os.path.relpath(guide, src)
        total_start = time.monotonic()
        for lang, text, line in blocks:
            origin = f"{rel}:{line}"
            if lang == "ini":
                apply_ini_block(text, cwd, substitute, origin)
                print(f"== {origin}: .ini values set", flush=True)
                continue
            if lang != "bash":
                continue
            apply_overrides(cwd)
            script = (f"trap 'pwd > {cwd_file}' EXIT\ncd {cwd}\n" + substitute(text, origin))
            print(f"== {origin}:\n{text.rstrip()}", flush=True)
            start = time.monotonic()
            try:
                r = subprocess.run(["bash", "-euo", "pipefail", "-c", script], env=env,
                                   timeout=BLOCK_TIMEOUT_S, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, errors="replace")
            except subprocess.TimeoutExpired:
                fail(f"{origin}: the block did not finish within {BLOCK_TIMEOUT_S} s")
            tail = "\n".join(r.stdout.rstrip().split("\n")[-25:])
            print(tail, flush=True)
            print(f"-- exit {r.returncode}, {time.monotonic() - start:.1f} s", flush=True)
            if r.returncode != 0:
                fail(f"{origin}: the block failed (exit status {r.returncode})")
            with open(cwd_file) as f:
                cwd = f.read().strip()
            apply_overrides(cwd)

        # Files the guide names: shipped ones, and the outputs the steps above wrote.
        text = open(guide, encoding="utf-8").read()
        missing = []
        for p in sorted(set(re.findall(r"/usr/local/share/mrpt_wifi/([\w./-]+\w)", text))):
            if not os.path.exists(os.path.join(share, p)):
                missing.append("/usr/local/share/mrpt_wifi/" + p)
        for p in sorted(set(re.findall(r"`(share/[\w./-]+\w)`", text))):
            if not os.path.exists(os.path.join(src, p)):
                missing.append(p)
        for p in sorted(set(re.findall(r"`((?:calib|calib_report|pf|live|devices)/[\w./-]+\w)`", text))):
            if not os.path.exists(os.path.join(cwd, p)):
                missing.append(f"{p} (not written by the guide's commands, in {cwd})")
        if missing:
            fail("the guide names files that do not exist: " + ", ".join(missing))
        print(f"guide {rel}: every block ran ({time.monotonic() - total_start:.0f} s)")
    finally:
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    p.kill()
        if sshd_pid:
            try:
                os.kill(sshd_pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
