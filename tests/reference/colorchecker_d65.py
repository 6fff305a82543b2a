#!/usr/bin/env python3
"""Independent reference for tests/cli/color_cli.rs: XYZ and CIELAB of the 24 ColorChecker
(BabelColor average) patches under CIE D65, CIE 1931 2 deg observer.

Written separately from the Rust code, in plain Python (no shared code, no numpy), from the
CIE 15:2018 definitions: X = k * sum S(l) R(l) xbar(l), k = 100 / sum S(l) ybar(l), summed
at 1 nm from 380 to 780 nm; S and R linearly interpolated to 1 nm, R held flat outside its
380-730 nm table (validation-box contract); CIELAB with the D65 white of the same sums.
Run: python3 tests/reference/colorchecker_d65.py > tests/data/colorchecker_d65_reference.csv
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "..", "data")


def read(name):
    rows = []
    header = None
    for line in open(os.path.join(DATA, name)):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if header is None:
            header = line.split(",")
            continue
        rows.append([float(v) for v in line.split(",")])
    return header, rows


def lerp_table(rows, col, nm, hold):
    xs = [r[0] for r in rows]
    if nm < xs[0]:
        return rows[0][col] if hold else 0.0
    if nm > xs[-1]:
        return rows[-1][col] if hold else 0.0
    for i in range(1, len(xs)):
        if nm <= xs[i]:
            t = (nm - xs[i - 1]) / (xs[i] - xs[i - 1])
            return rows[i - 1][col] + t * (rows[i][col] - rows[i - 1][col])
    return rows[-1][col]


_, cmf = read("cie1931_2deg_cmf_1nm.csv")
cmf = {int(r[0]): r[1:] for r in cmf}
_, d65 = read("illuminant_d65.csv")
header, cc = read("colorchecker_babelcolor_average.csv")

S = {nm: lerp_table(d65, 1, nm, False) for nm in range(380, 781)}
k = 100.0 / sum(S[nm] * cmf[nm][1] for nm in range(380, 781))
white = [k * sum(S[nm] * cmf[nm][i] for nm in range(380, 781)) for i in range(3)]


def f(t):
    e = 216.0 / 24389.0
    return t ** (1.0 / 3.0) if t > e else (24389.0 / 27.0 * t + 16.0) / 116.0


print("patch,X,Y,Z,L,a,b")
for p in range(24):
    R = {nm: lerp_table(cc, p + 1, nm, True) for nm in range(380, 781)}
    xyz = [k * sum(S[nm] * R[nm] * cmf[nm][i] for nm in range(380, 781)) for i in range(3)]
    fx, fy, fz = (f(xyz[i] / white[i]) for i in range(3))
    lab = (116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz))
    print("%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f" % ((p + 1,) + tuple(xyz) + lab))
