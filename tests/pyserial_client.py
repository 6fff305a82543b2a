#!/usr/bin/env python3
"""A CS-100A client that is not metamer's own driver: pyserial on the device path.

Usage: pyserial_client.py DEVICE X Y Z [Y_REL_TOL XY_TOL]

Sends MDS,04 (measuring mode: absolute Yxy) and MES (measure), checks that the replies have
the meter's format, `OK00` and `OK00,Y,x,y` (Y with its sign column, x and y with four
decimals and no leading zero), and that Y, x, y match the light X, Y, Z given: x = X/(X+Y+Z),
y = Y/(X+Y+Z). Tolerances default to the meter's printed precision (4 significant digits of
Y, 4 decimals of x and y). Prints the reading; exits 1 on any mismatch.
"""

import errno
import re
import sys
import termios

import serial

MEASUREMENT = re.compile(r"^OK00,([ -] *\d*\.?\d+),([ -]\.\d{4}),([ -]\.\d{4})\r\n$")


class PtySerial(serial.Serial):
    """pyserial's port, except that a Linux pty's EINVAL for the 7E2 termios is ignored:
    the line settings mean nothing on a pty, and pyserial would close the port on it."""

    def _reconfigure_port(self, force_update=False):
        try:
            super()._reconfigure_port(force_update)
        except (termios.error, OSError) as e:
            if e.args[0] != errno.EINVAL:
                raise


def open_port(path):
    return PtySerial(
        path,
        baudrate=4800,
        bytesize=serial.SEVENBITS,
        parity=serial.PARITY_EVEN,
        stopbits=serial.STOPBITS_TWO,
        timeout=5,
    )


def ask(port, command):
    port.write(command)
    reply = port.readline().decode("ascii")
    if not reply.endswith("\r\n"):
        fail(f"{command!r}: no complete reply in time, got {reply!r}")
    return reply


def fail(message):
    print(f"pyserial client: {message}", file=sys.stderr)
    sys.exit(1)


def main(argv):
    if len(argv) not in (5, 7):
        fail(__doc__.strip().splitlines()[2])
    path = argv[1]
    big_x, big_y, big_z = (float(v) for v in argv[2:5])
    y_tol, xy_tol = (float(v) for v in argv[5:7]) if len(argv) == 7 else (5e-4, 6e-5)
    total = big_x + big_y + big_z
    want = (big_y, big_x / total, big_y / total)

    port = open_port(path)
    reply = ask(port, b"MDS,04\r\n")
    if reply != "OK00\r\n":
        fail(f"MDS,04 answered {reply!r}, expected 'OK00\\r\\n'")
    reply = ask(port, b"MES\r\n")
    m = MEASUREMENT.match(reply)
    if not m:
        fail(f"MES answered {reply!r}, not OK00,Y,x,y")
    got = tuple(float(g.replace(" ", "")) for g in m.groups())
    port.close()

    if abs(got[0] - want[0]) > y_tol * want[0]:
        fail(f"Y {got[0]} vs {want[0]:.6g} (relative tolerance {y_tol})")
    for name, g, w in (("x", got[1], want[1]), ("y", got[2], want[2])):
        if abs(g - w) > xy_tol:
            fail(f"{name} {g} vs {w:.6f} (tolerance {xy_tol})")
    print(f"Y {got[0]} x {got[1]:.4f} y {got[2]:.4f}")


if __name__ == "__main__":
    main(sys.argv)
