#!/usr/bin/env python3
"""Held-out error of `metamer light fit --model auto` in the IES file it writes.

For each distribution: nine readings per plane (-80 ... 80 deg in 20 deg steps) go through
the binary (`light fit --model auto --ies --width-m 0.5 --height-m 0.5 --luminance 1000`);
the IES file is read here by a reader of its own (LM-63 keyword lines, TILT=NONE, the
numbers in order) and its candela at the angles between the readings (10, 30, 50, 70 deg
in C0, C90, C180, C270, all on the file's grid) is compared with the truth
I = I0 * f(x) * cos(gamma), I0 = 1000 cd/m2 * 0.25 m2. The error is relative to I0.

The last column is `--model lobes`, the richest of the half-plane models, for comparison.

Usage: python3 benches/light/heldout_ies.py [path/to/metamer]
"""

import json
import math
import os
import subprocess
import sys
import tempfile

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/metamer"


def cos(d):
    return math.cos(math.radians(d))


def sin(d):
    return math.sin(math.radians(d))


# (name, horizontal f(x), vertical f(x)) in the signed angle x, degrees; f(0) = 1.
SKEWED = [
    ("cos^0.8(1+0.1 sin) ; exp(-(g/0.9)^2)(1-0.05 sin)",
     lambda x: cos(x) ** 0.8 * (1 + 0.1 * sin(x)),
     lambda x: math.exp(-(math.radians(x) / 0.9) ** 2) * (1 - 0.05 * sin(x))),
    ("cos^1.5(1+0.15 sin) ; (0.7 cos+0.3 cos^6)(1+0.08 sin)",
     lambda x: cos(x) ** 1.5 * (1 + 0.15 * sin(x)),
     lambda x: (0.7 * cos(x) + 0.3 * cos(x) ** 6) * (1 + 0.08 * sin(x))),
    ("batwing cos^0.5(1+0.3 sin^2) ; exp(-(g/1.1)^4)(1-0.1 sin)",
     lambda x: cos(x) ** 0.5 * (1 + 0.3 * sin(x) ** 2),
     lambda x: math.exp(-(math.radians(x) / 1.1) ** 4) * (1 - 0.1 * sin(x))),
    ("cos^1.2 tilted 10 deg ; exp(-(g/0.7)^2)(1+0.05 sin 2g)",
     lambda x: cos(x - 10) ** 1.2 / cos(10) ** 1.2,
     lambda x: math.exp(-(math.radians(x) / 0.7) ** 2) * (1 + 0.05 * sin(2 * x))),
    ("Gaussian 0.1 rad off the normal ; cos^2(1+0.12 sin-0.05 sin^2)",
     lambda x: math.exp(-((math.radians(x) - 0.1) / 0.8) ** 2) / math.exp(-(0.1 / 0.8) ** 2),
     lambda x: cos(x) ** 2 * (1 + 0.12 * sin(x) - 0.05 * sin(x) ** 2)),
    ("cos-power truth: cos^1.7 / cos^0.8 ; cos^2.5 / cos^1.2",
     lambda x: cos(x) ** (1.7 if x >= 0 else 0.8),
     lambda x: cos(x) ** (2.5 if x >= 0 else 1.2)),
]


def read_ies(path):
    """{(C, gamma): candela} of an LM-63 file with TILT=NONE."""
    lines = open(path, encoding="latin-1").read().splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("TILT="))
    assert lines[k].strip() == "TILT=NONE", lines[k]
    v = [float(t) for l in lines[k + 1:] for t in l.replace(",", " ").split()]
    lamps, lumens, mult, ng, nc = v[0], v[1], v[2], int(v[3]), int(v[4])
    v = v[13:]  # ten values of the first line, three of the second
    gammas, cs, cd = v[:ng], v[ng:ng + nc], v[ng + nc:]
    assert len(cd) == ng * nc, (len(cd), ng, nc)
    return {(c, g): cd[i * ng + j] * mult for i, c in enumerate(cs) for j, g in enumerate(gammas)}


def main():
    i0 = 1000 * 0.5 * 0.5
    with tempfile.TemporaryDirectory() as d:
        print("| distribution | auto chose | auto: largest error, % of I0 | lobes (richest half-plane model) |")
        print("|---|---|---|---|")
        for name, fh, fv in SKEWED:
            csv = os.path.join(d, "f.csv")
            with open(csv, "w") as f:
                f.write("angle_deg,horizontal,vertical\n")
                for x in range(-80, 81, 20):
                    f.write(f"{x},{fh(x)!r},{fv(x)!r}\n")
            ies, js = os.path.join(d, "f.ies"), os.path.join(d, "f.json")
            errors = []
            for m in ("auto", "lobes"):
                subprocess.run([BIN, "light", "fit", "--falloff", csv, "--model", m, "-o", js,
                                "--ies", ies, "--width-m", "0.5", "--height-m", "0.5",
                                "--luminance", "1000", "--force"],
                               check=True, stdout=subprocess.DEVNULL)
                if m == "auto":
                    model = json.load(open(js))["model"]
                table = read_ies(ies)
                worst = 0.0
                for c, f, sign in [(0, fh, 1), (180, fh, -1), (90, fv, 1), (270, fv, -1)]:
                    for g in (10, 30, 50, 70):
                        want = i0 * f(sign * g) * cos(g)
                        worst = max(worst, abs(table[(c, g)] - want) / i0)
                errors.append(worst)
            print(f"| {name} | {model} | {100 * errors[0]:.2f} | {100 * errors[1]:.2f} |")


if __name__ == "__main__":
    main()
