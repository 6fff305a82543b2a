#!/usr/bin/env python3
"""Makes the `metamer validate` fixtures from 24 pairs of Sharma, Wu & Dalal (2005), 1–13
and 15–25: pair 14 lies exactly on CIEDE2000's mean-hue discontinuity (|h1' - h2'| = 180°,
a* = -0.0010 against 0.0010), where any rounding of XYZ lands on one side or the other (its
neighbours 13 and 15 give 4.8045 and 4.7461). The k-th pair used is patch k: its first colour is the box's reading of patch k, its second the display's, both
converted from CIELAB to XYZ relative to the display's white (D65, Y = 100) by CIE 15's
inverse formulas. expected.csv holds each pair's ΔE*ab (Euclidean distance of the published
Lab values) and its published ΔE00, so the test needs nothing of metamer's colour code.
The display readings carry sd columns (0.1 % of each value, n = 3) so intervals exist.

Run from the repository root: python3 tests/reference/validate_fixture.py
"""
import csv
import math

WHITE = (95.047, 100.0, 108.883)


def lab_to_xyz(l, a, b):
    eps, kappa = 216 / 24389, 24389 / 27
    fy = (l + 16) / 116
    fx, fz = fy + a / 500, fy - b / 200
    inv = lambda f: f ** 3 if f ** 3 > eps else (116 * f - 16) / kappa
    yr = ((l + 16) / 116) ** 3 if l > kappa * eps else l / kappa
    return (inv(fx) * WHITE[0], yr * WHITE[1], inv(fz) * WHITE[2])


rows = [r for r in open("tests/data/sharma2005_ciede2000.csv") if not r.startswith("#")]
all_pairs = list(csv.DictReader(rows))
pairs = all_pairs[:13] + all_pairs[14:25]
box = ["patch,X,Y,Z"]
display = ["patch,X,Y,Z,sd_X,sd_Y,sd_Z,n", "white,%.4f,%.4f,%.4f,0,0,0,1" % WHITE]
expected = ["patch,de76,de00"]
for k, p in enumerate(pairs, 1):
    v = {key: float(x) for key, x in p.items()}
    x1 = lab_to_xyz(v["L1"], v["a1"], v["b1"])
    x2 = lab_to_xyz(v["L2"], v["a2"], v["b2"])
    assert min(x1 + x2) > 0, (k, x1, x2)
    box.append("%d,%.10f,%.10f,%.10f" % ((k,) + x1))
    sd = tuple(0.001 * x for x in x2)
    display.append("%d,%.10f,%.10f,%.10f,%.10f,%.10f,%.10f,3" % ((k,) + x2 + sd))
    de76 = math.dist((v["L1"], v["a1"], v["b1"]), (v["L2"], v["a2"], v["b2"]))
    expected.append("%d,%.6f,%.4f" % (k, de76, v["de00"]))
header = "# Sharma, Wu & Dalal (2005) pairs 1-13 and 15-25 as readings; made by tests/reference/validate_fixture.py\n"
for name, lines in [("box", box), ("display", display), ("expected", expected)]:
    with open("tests/data/validate/%s.csv" % name, "w") as f:
        f.write(header + "\n".join(lines) + "\n")
