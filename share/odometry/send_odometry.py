#!/usr/bin/env python3
"""Send a robot's wheel odometry to mrpt_wifi's CWiFiOdometryUdpSensor (share/odometry/README.md).

One UDP datagram per pose, one ASCII line each:

    MRPT_WIFI_ODO 1 SEQ T X Y PHI VX VY OMEGA

Use it three ways:

  * import it in the robot's own Python software:

        from send_odometry import OdometrySender
        with OdometrySender("127.0.0.1", 5501) as odo:
            odo.send(x, y, phi, vx, vy, omega)      # at every new wheel odometry pose

  * pipe poses into it from any program, one "X Y PHI [VX VY OMEGA]" line per pose on stdin:

        my_robot_odometry | python3 send_odometry.py --stdin

  * try it: without --stdin it drives an example circle (no robot needed).

Python 3 standard library only. Every loop is bounded (--count); the default destination is this
machine (127.0.0.1), where rawlog-grabber or wifi-localize listens.
"""

import argparse
import math
import socket
import sys
import time

PROTOCOL_VERSION = 1
MAX_DATAGRAM_BYTES = 512  # the receiver ignores longer datagrams


class OdometrySender:
    """Sends poses as MRPT_WIFI_ODO lines over UDP, numbering them 0, 1, 2, ..."""

    def __init__(self, host="127.0.0.1", port=5501):
        infos = socket.getaddrinfo(host, port, 0, socket.SOCK_DGRAM)
        family, _, _, _, self.address = infos[0]
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        self.seq = 0

    def line(self, x, y, phi, vx=0.0, vy=0.0, omega=0.0, t=None):
        """The datagram's text for one pose (and advances the sequence number)."""
        values = [x, y, phi, vx, vy, omega]
        if not all(math.isfinite(float(v)) for v in values):
            raise ValueError("odometry values must be finite numbers: %r" % (values,))
        stamp = time.time() if t is None else float(t)
        text = "MRPT_WIFI_ODO %d %d %.6f %.6f %.6f %.8f %.6f %.6f %.8f\n" % (
            PROTOCOL_VERSION, self.seq, stamp, x, y, phi, vx, vy, omega)
        self.seq += 1
        return text

    def send(self, x, y, phi, vx=0.0, vy=0.0, omega=0.0, t=None):
        """Sends one pose: x, y [m] and phi [rad] of the robot in its odometry frame, the
        body-frame velocity vx, vy [m/s], omega [rad/s]; t: the sender's time [s] (default now).
        Returns the line sent."""
        text = self.line(x, y, phi, vx, vy, omega, t)
        data = text.encode("ascii")
        assert len(data) <= MAX_DATAGRAM_BYTES
        self.sock.sendto(data, self.address)
        return text

    def close(self):
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def parse_pose_line(text, number):
    """'X Y PHI [VX VY OMEGA]' -> six floats; raises ValueError naming the line."""
    fields = text.split()
    if len(fields) not in (3, 6):
        raise ValueError("stdin line %d: expected 'X Y PHI [VX VY OMEGA]', got %r"
                         % (number, text.rstrip("\n")))
    try:
        values = [float(f) for f in fields]
    except ValueError:
        raise ValueError("stdin line %d: not a number in %r" % (number, text.rstrip("\n")))
    return values + [0.0] * (6 - len(values))


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Send wheel odometry to mrpt_wifi's CWiFiOdometryUdpSensor "
                    "(MRPT_WIFI_ODO 1 lines over UDP).")
    parser.add_argument("--host", default="127.0.0.1",
                        help="receiver address: the sensor's udp_bind_address (127.0.0.1)")
    parser.add_argument("--port", type=int, default=5501,
                        help="receiver port: the sensor's udp_port (5501)")
    parser.add_argument("--count", type=int, default=200,
                        help="send at most this many poses, then stop (200)")
    parser.add_argument("--rate", type=float, default=20.0,
                        help="example circle: poses per second (20); 0 = as fast as possible")
    parser.add_argument("--radius", type=float, default=1.0,
                        help="example circle: radius in m (1.0)")
    parser.add_argument("--speed", type=float, default=0.3,
                        help="example circle: speed in m/s (0.3)")
    parser.add_argument("--stdin", action="store_true",
                        help="send the poses read from stdin, 'X Y PHI [VX VY OMEGA]' per line, "
                             "instead of the example circle (stops at the end of input or "
                             "after --count poses)")
    parser.add_argument("--print", dest="echo", action="store_true",
                        help="print every line sent on stdout")
    args = parser.parse_args(argv)
    if args.count < 0 or args.rate < 0 or args.radius <= 0:
        parser.error("--count and --rate must be >= 0 and --radius > 0")
    if not 0 < args.port < 65536:
        parser.error("--port must be in 1..65535")

    sent = 0
    try:
        with OdometrySender(args.host, args.port) as odo:
            if args.stdin:
                for number, text in enumerate(sys.stdin, start=1):
                    if sent >= args.count:
                        break
                    if not text.strip() or text.lstrip().startswith("#"):
                        continue
                    line = odo.send(*parse_pose_line(text, number))
                    sent += 1
                    if args.echo:
                        sys.stdout.write(line)
            else:
                omega = args.speed / args.radius
                period = 1.0 / args.rate if args.rate > 0 else 0.0
                start = time.monotonic()
                for i in range(args.count):
                    t = i * (period if period > 0 else 0.05)
                    phi = omega * t
                    x = args.radius * math.sin(phi)
                    y = args.radius * (1.0 - math.cos(phi))
                    wrapped = math.atan2(math.sin(phi), math.cos(phi))
                    line = odo.send(x, y, wrapped, args.speed, 0.0, omega)
                    sent += 1
                    if args.echo:
                        sys.stdout.write(line)
                    if period > 0:
                        delay = start + (i + 1) * period - time.monotonic()
                        if delay > 0:
                            time.sleep(delay)
    except (OSError, ValueError) as e:
        sys.stderr.write("send_odometry.py: %s\n" % e)
        return 1
    sys.stderr.write("send_odometry.py: %d poses sent to %s:%d\n" % (sent, args.host, args.port))
    return 0


if __name__ == "__main__":
    sys.exit(main())
