#!/usr/bin/env python3
"""XYZ of 10 nm spectra: metamer against ArgyllCMS and colour-science.

The stimuli are what an i1Pro reads off the 24 ColorChecker patches lit by a display white:
the `ips-lcd` display white (data/display_white_ips_lcd.csv, 1 nm) times the BabelColor
average reflectances (data/colorchecker_babelcolor_average.csv, 10 nm, interpolated
linearly and held flat beyond 730 nm as the validation box does), plus the white itself.
The "1 nm truth" is that product summed at 1 nm over 380-780 nm. Each method sees only the
product sampled at 380, 390, ..., 730 nm (36 bands, an i1Pro's grid).

Methods:
  metamer cie15     `metamer color xyz --json` (default: Sprague, ends held, 360-830 nm)
  metamer linear    `metamer color xyz --method linear` (linear, zero outside, 380-780 nm)
  argyll spec2cie   ArgyllCMS's `spec2cie` on an emissive .sp file (MEAS_TYPE EMISSION);
                    it prints emissive XYZ in units of 1000 cd/m^2, scaled back here
  cs Integration    colour-science `sd_to_XYZ(method="Integration", k=683)`, illuminant
                    equal energy (align to the CMFs: Sprague, constant extrapolation)
  cs ASTM E308      colour-science `sd_to_XYZ(method="ASTM E308", k=683)`: ASTM E2022
                    weights at 10 nm computed from the 1 nm CMFs over E308's 360-780 nm,
                    weights beyond the data added to the end bands
  cs ASTM E308 full the same over the CMFs' 360-830 nm (use_practice_range=False)

Prints, per method, the X, Y, Z differences in % (mean and max of |d| over the 25 stimuli)
against metamer cie15 and against the 1 nm truth, and CIEDE2000 (each method's Lab against
its own white, the display white's XYZ by the same method), and writes every XYZ as JSON.

Run from the repository root (needs target/release/metamer, `argyll`, `colour-science`):
    python3 protocols/color/reference/sampled_xyz.py [--json out.json] [--skip-argyll]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import warnings

warnings.filterwarnings("ignore")
import numpy as np  # noqa: E402
import colour  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
METAMER = os.environ.get("METAMER", os.path.join(ROOT, "target", "release", "metamer"))
BANDS = list(range(380, 731, 10))


def table(name):
    rows, header = [], None
    for line in open(os.path.join(ROOT, "data", name), encoding="utf-8"):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if header is None:
            header = line.split(",")
            continue
        rows.append([float(v) for v in line.split(",")])
    return header, np.array(rows)


def stimuli():
    """(names, 1 nm wavelengths 380-780, 1 nm stimuli [25, 401])."""
    _, white = table("display_white_ips_lcd.csv")
    header, cc = table("colorchecker_babelcolor_average.csv")
    nm = np.arange(380, 781)
    w = np.interp(nm, white[:, 0], white[:, 1], left=0.0, right=0.0)
    names, rows = ["display white"], [w]
    for p in range(24):
        r = np.interp(nm, cc[:, 0], cc[:, p + 1])  # np.interp holds the end values
        names.append(header[p + 1])
        rows.append(w * r)
    return names, nm, np.array(rows)


def truth(nm, rows):
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    cmf = np.array([cmfs[float(l)] for l in nm])
    return 683.0 * rows @ cmf


def sampled(nm, rows):
    idx = [int(b - nm[0]) for b in BANDS]
    return rows[:, idx]


def metamer(samples, method):
    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
        f.write("# stimuli for protocols/color/reference/sampled_xyz.py\n")
        f.write("nm," + ",".join(f"s{i}" for i in range(len(samples))) + "\n")
        for j, b in enumerate(BANDS):
            f.write(f"{b}," + ",".join(repr(float(s[j])) for s in samples) + "\n")
        path = f.name
    out = subprocess.run(
        [METAMER, "color", "xyz", path, "--json", "--method", method],
        check=True, capture_output=True, text=True,
    ).stdout
    os.unlink(path)
    return np.array([json.loads(line)["XYZ"] for line in out.splitlines() if line.strip()])


def argyll(samples):
    lines = [
        "SPECT", "", 'DESCRIPTOR "metamer sampled_xyz.py"', 'ORIGINATOR "metamer"',
        'KEYWORD "MEAS_TYPE"', 'MEAS_TYPE "EMISSION"',
        'KEYWORD "SPECTRAL_BANDS"', f'SPECTRAL_BANDS "{len(BANDS)}"',
        'KEYWORD "SPECTRAL_START_NM"', f'SPECTRAL_START_NM "{BANDS[0]:.6f}"',
        'KEYWORD "SPECTRAL_END_NM"', f'SPECTRAL_END_NM "{BANDS[-1]:.6f}"',
        'KEYWORD "SPECTRAL_NORM"', 'SPECTRAL_NORM "1.000000"',
        f"NUMBER_OF_FIELDS {len(BANDS)}", "BEGIN_DATA_FORMAT",
        " ".join(f"SPEC_{b:03d}" for b in BANDS), "END_DATA_FORMAT", "",
        f"NUMBER_OF_SETS {len(samples)}", "BEGIN_DATA",
    ]
    lines += [" ".join(f"{v:.10g}" for v in s) for s in samples]
    lines.append("END_DATA")
    with tempfile.TemporaryDirectory() as d:
        src, dst = os.path.join(d, "in.sp"), os.path.join(d, "out.sp")
        open(src, "w").write("\n".join(lines) + "\n")
        subprocess.run(["spec2cie", src, dst], check=True, capture_output=True)
        text = open(dst).read().split()
    fields = text[text.index("BEGIN_DATA_FORMAT") + 1:text.index("END_DATA_FORMAT")]
    data = text[text.index("BEGIN_DATA") + 1:text.index("END_DATA")]
    n = len(fields)
    ix = [fields.index(k) for k in ("XYZ_X", "XYZ_Y", "XYZ_Z")]
    rows = [data[i * n:(i + 1) * n] for i in range(len(data) // n)]
    return 1000.0 * np.array([[float(r[k]) for k in ix] for r in rows])


def colour_science(samples, method, **kw):
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    ones = colour.sd_ones(cmfs.shape)
    out = []
    for s in samples:
        sd = colour.SpectralDistribution(dict(zip(BANDS, s)))
        # k given: colour-science returns absolute values divided by 100.
        out.append(100.0 * colour.sd_to_XYZ(sd, cmfs, ones, k=683, method=method, **kw))
    return np.array(out)


def de00(xyz, white):
    lab = colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xy(white))
    return lab


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--json")
    ap.add_argument("--skip-argyll", action="store_true")
    a = ap.parse_args()
    names, nm, rows = stimuli()
    samples = sampled(nm, rows)
    results = {"1 nm truth": truth(nm, rows)}
    results["metamer cie15"] = metamer(samples, "cie15")
    results["metamer linear"] = metamer(samples, "linear")
    if not a.skip_argyll:
        results["argyll spec2cie"] = argyll(samples)
    results["cs Integration"] = colour_science(samples, "Integration")
    results["cs ASTM E308"] = colour_science(samples, "ASTM E308")
    results["cs ASTM E308 full"] = colour_science(
        samples, "ASTM E308", use_practice_range=False)

    def lab(xyz):
        w = xyz[0]
        return colour.XYZ_to_Lab(xyz / w[1], colour.XYZ_to_xy(w))

    ref = results["metamer cie15"]
    tru = results["1 nm truth"]
    print("| method | white X, Y, Z vs metamer cie15 (%) | mean / max abs dX, dY, dZ vs metamer cie15 (%) "
          "| dE00 vs metamer cie15 mean / max | mean abs dX, dY, dZ vs 1 nm truth (%) | dE00 vs 1 nm truth mean / max |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, xyz in results.items():
        d = 100.0 * (xyz - ref) / ref
        dt = 100.0 * (xyz - tru) / tru
        e = colour.delta_E(lab(xyz), lab(ref), method="CIE 2000")
        et = colour.delta_E(lab(xyz), lab(tru), method="CIE 2000")
        white = ", ".join(f"{v:+.3f}" for v in d[0])
        mean = ", ".join(f"{v:.3f}" for v in np.abs(d).mean(0))
        mx = ", ".join(f"{v:.3f}" for v in np.abs(d).max(0))
        tmean = ", ".join(f"{v:.3f}" for v in np.abs(dt).mean(0))
        print(f"| {name} | {white} | {mean} / {mx} | {e[1:].mean():.4f} / {e[1:].max():.4f} "
              f"| {tmean} | {et[1:].mean():.4f} / {et[1:].max():.4f} |")
    if a.json:
        json.dump({"names": names, "bands_nm": BANDS, "samples": samples.tolist(),
                   "xyz": {k: v.tolist() for k, v in results.items()}},
                  open(a.json, "w"), indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
