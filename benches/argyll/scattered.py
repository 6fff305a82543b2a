#!/usr/bin/env python3
"""metamer's models against ArgyllCMS `colprof -as` at equal patches, on scattered sets.

The sets come from `tests/display/scattered_fit.rs` (seeded scrambled-Halton drive values plus the
cube's corners, 50/200/1000 patches, read noise-free from each simulated display; the
held-out set is 500 seeded random drive values with the white first; each set's
`fit-noisy.ti3` is the same patches read with the simulated CS-100A's repeatability, seeded):
  METAMER_SCATTERED_OUT=target/scattered cargo test --release --test display \
      -- --ignored scattered_fit::print_held_out_table
then, from the repository root, after `apt-get install argyll`:
  python3 benches/argyll/scattered.py [--dir target/scattered] [--models shaper-matrix lut auto]
      [--noisy]
With --noisy every fit (metamer's and colprof's) is on `fit-noisy.ti3`; the held-out set
stays noise-free, so the score is the model's error, not the held-out readings' noise.
For each set it fits metamer's models (`metamer fit`, held-out ΔE00 by `metamer verify
--json`) and profiles the same .ti3 with `colprof -qm -as` (run as an external program),
looks the held-out drive values up with `xicclu -ff -iA -pX` (display-absolute XYZ) and
computes ΔE00 with `metamer color delta-e`, CIELAB relative to the measured white in both.
Prints a Markdown table.
"""

import argparse
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(__file__))
from compare import METAMER, delta_e00, lab, run, stats  # noqa: E402


def read_ti3(path):
    """Drive values 0–1 and absolute XYZ of a .ti3 as metamer's write_ti3 writes it."""
    text = open(path).read().splitlines()
    lum = [l for l in text if l.startswith("LUMINANCE_XYZ_CDM2")][0]
    scale = float(lum.split('"')[1].split()[1]) / 100
    fields = text[text.index("BEGIN_DATA_FORMAT") + 1].split()
    start, end = text.index("BEGIN_DATA"), text.index("END_DATA")
    rows = [dict(zip(fields, l.split())) for l in text[start + 1:end]]
    rgb = [[float(r[k]) / 100 for k in ("RGB_R", "RGB_G", "RGB_B")] for r in rows]
    xyz = [[float(r[k]) * scale for k in ("XYZ_X", "XYZ_Y", "XYZ_Z")] for r in rows]
    return rgb, xyz


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--dir", default="target/scattered")
    p.add_argument("--models", nargs="+", default=["shaper-matrix", "lut", "auto"])
    p.add_argument("--noisy", action="store_true",
                   help="fit on fit-noisy.ti3 (CS-100A noise) instead of fit.ti3")
    a = p.parse_args()
    fit = "fit-noisy" if a.noisy else "fit"
    if shutil.which("colprof") is None:
        sys.exit("ArgyllCMS colprof is not installed (apt-get install argyll)")
    print("| display | patches | colprof -as | " + " | ".join(a.models) + " |")
    print("| --- | --- | --- |" + " --- |" * len(a.models))
    for name in sorted(os.listdir(a.dir)):
        d = os.path.join(a.dir, name)
        if not os.path.isdir(d):
            continue
        rgb, xyz = read_ti3(os.path.join(d, "heldout.ti3"))
        white, rgb, xyz = xyz[0], rgb[1:], xyz[1:]
        run(["colprof", "-qm", "-as", "-D", "as", fit], cwd=d)
        out = run(["xicclu", "-v0", "-ff", "-iA", "-pX", os.path.join(d, f"{fit}.icc")],
                  input="".join(f"{r:.8f} {g:.8f} {b:.8f}\n" for r, g, b in rgb))
        pred = [[float(v) for v in l.split()[:3]] for l in out.strip().splitlines()]
        argyll = stats(delta_e00([(lab(m, white), lab(q, white)) for m, q in zip(xyz, pred)], d))
        cells = [f"{argyll['mean']:.3f}"]
        for model in a.models:
            prof = os.path.join(d, f"{model}-{fit}.json")
            log = run([METAMER, "fit", "--model", model, "--measurements",
                       os.path.join(d, f"{fit}.ti3"), "-o", prof, "--force"])
            chose = [l for l in log.splitlines() if l.startswith("chose ")]
            v = json.loads(run([METAMER, "verify", "--profile", prof, "--measurements",
                                os.path.join(d, "heldout.ti3"), "--json"]))
            # verify's mean includes the white in first place (ΔE00 ≈ 0): take it out.
            n = v["patches"]
            mean = v["de00"]["mean"] * n / (n - 1)
            tag = f" ({chose[0].split()[1].rstrip(':')})" if chose else ""
            cells.append(f"{mean:.3f}{tag}")
        dsp, n = name.rsplit("-", 1)
        print(f"| {dsp} | {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
