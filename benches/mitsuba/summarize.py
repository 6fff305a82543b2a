#!/usr/bin/env python3
"""Markdown tables of a run.sh output directory (per-patch agreement, samples, times).

    python3 benches/mitsuba/summarize.py target/mitsuba-bench
"""

import glob
import json
import os
import re
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "target/mitsuba-bench"
    runs = sorted(glob.glob(os.path.join(out, "mitsuba_*_*.json")))
    runs = [r for r in runs if re.search(r"mitsuba_(cmf|light)_\d+\.json$", r)]
    if not runs:
        raise SystemExit(f"no mitsuba_*_N.json in {out}")
    res = {}
    for r in runs:
        wl, n = re.search(r"mitsuba_(\w+)_(\d+)\.json$", r).groups()
        res[(wl, int(n))] = load(r)
    keys = sorted(res, key=lambda k: (k[1], k[0]))

    print("| run | Mitsuba samples (white + 24) | Mitsuba render s | metamer samples (24) | metamer s "
          "| ΔE*ab max | ΔE*ab mean | white ΔE*ab |")
    print("|---|---|---|---|---|---|---|---|")
    for k in keys:
        m = res[k]
        c = m["comparison"]
        mm = load(os.path.join(out, f"metamer_{k[1]}.json"))
        ms = sum(p["samples"] for p in m["patches"]) + m["white_samples"]
        mms = sum(p["samples"] for p in mm["patches"])
        wde = _white_de(m["white"], mm["white"])
        print(f"| {k[0]} #{k[1]} | {ms / 1e6:.1f} M | {m['seconds_render']:.0f} | {mms / 1e6:.2f} M "
              f"| {mm['seconds']:.0f} | {c['max_de_common_white']:.3f} | {c['mean_de_common_white']:.3f} "
              f"| {wde:.3f} |")
    print()
    head = " | ".join(f"{wl} #{n} ΔE / hw" for wl, n in keys)
    print(f"| patch | {head} |")
    print("|---" * (len(keys) + 1) + "|")
    for i in range(24):
        cells = []
        for k in keys:
            row = res[k]["comparison"]["rows"][i]
            cells.append(f"{row['de_common_white']:.3f} / {row['combined_hw95']:.3f}")
        print(f"| {i + 1} | " + " | ".join(cells) + " |")
    pooled(out, res)


def pooled(out, res):
    """All Mitsuba runs against all metamer runs: averaging shrinks the noise, so a bias
    between the renderers shows up sharper than in any single pair."""
    import numpy as np

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from validation_box import de76, lab  # noqa: E402

    mms = [load(p) for p in sorted(glob.glob(os.path.join(out, "metamer_*.json")))]
    white = np.mean([m["white"] for m in mms], axis=0)
    print()
    print(f"Pooled: {len(res)} Mitsuba runs against {len(mms)} metamer runs (white: mean of "
          "metamer's whites)")
    print()
    print("| patch | metamer Y cd/m2 | Mitsuba Y cd/m2 | ΔY % | ΔE*ab | 95 % hw of the difference |")
    print("|---|---|---|---|---|---|")
    des = []
    for i in range(24):
        a = np.mean([m["patches"][i]["XYZ"] for m in mms], axis=0)
        b = np.mean([r["patches"][i]["XYZ"] for r in res.values()], axis=0)
        hw_a = np.sqrt(np.mean([m["patches"][i]["de_ci95"] ** 2 for m in mms]) / len(mms))
        hw_b = np.sqrt(np.mean([r["patches"][i]["de_ci95"] ** 2 for r in res.values()]) / len(res))
        de = de76(lab(a, white), lab(b, white))
        des.append(de)
        print(f"| {i + 1} | {a[1]:.4f} | {b[1]:.4f} | {100 * (b[1] / a[1] - 1):+.2f} | {de:.3f} "
              f"| {np.hypot(hw_a, hw_b):.3f} |")
    print(f"\nPooled ΔE*ab: max {max(des):.3f}, mean {np.mean(des):.3f}")


def _white_de(a, ref):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from validation_box import de76, lab  # noqa: E402 (numpy only, no Mitsuba)

    return de76(lab(a, ref), lab(ref, ref))


if __name__ == "__main__":
    main()
