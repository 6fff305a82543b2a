#!/usr/bin/env python3
"""metamer's display models against ArgyllCMS's matrix/shaper profiles, on the same readings.

For every simulated monitor, ramp budget and metamer model this script
  1. runs `metamer characterize` (simulated CS-100A with its noise) into OUT/...,
  2. keeps the rows of its readings.ti3 that the fit saw (the 48 held-out verification
     patches, labelled `random N` / `ColorChecker ...` in log.jsonl, are removed) and profiles
     them with ArgyllCMS `colprof` (run as an external program, nothing of it is used here),
  3. looks the 48 held-out drive values up in each Argyll profile with
     `xicclu -ff -iA -pX` (forward, display-absolute: XYZ in cd/m²),
  4. computes ΔE00 of metamer's prediction and of Argyll's against the measured XYZ, both in
     CIELAB relative to the same white (summary.json's white_xyz, the measured white metamer
     verifies against), with `metamer color delta-e` (checked against Sharma et al. 2005).

Usage (from the repository root, after `cargo build --release` and `apt-get install argyll`):
  python3 benches/argyll/compare.py [--out target/argyll-bench] [--display ips-lcd ...]
      [--steps 3 5 9 17] [--model plcc matrix-lsq lut] [--seeds 1] [--algos s S g]
      [--clut 9]
Prints a Markdown table and writes OUT/results.json (one record per set and method).
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

METAMER = os.environ.get("METAMER", "./target/release/metamer")
VERIFICATION_PREFIXES = ("random", "ColorChecker")


def run(cmd, **kw):
    """Runs a command; on failure prints its output and stops (nothing is guessed)."""
    p = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stdout}\n{p.stderr}")
    return p.stdout


def lab(xyz, white):
    """CIE 1976 L*a*b* (CIE 15:2004), relative to `white` (same units as xyz)."""
    eps, kappa = 216 / 24389, 24389 / 27

    def f(t):
        return t ** (1 / 3) if t > eps else (kappa * t + 16) / 116

    fx, fy, fz = (f(v / w) for v, w in zip(xyz, white))
    return (116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz))


def delta_e00(pairs, workdir):
    """CIEDE2000 of Lab pairs by `metamer color delta-e` (one call for all pairs)."""
    path = os.path.join(workdir, "pairs.csv")
    with open(path, "w") as f:
        f.write("L1,a1,b1,L2,a2,b2\n")
        for a, b in pairs:
            f.write(",".join(f"{v:.10f}" for v in (*a, *b)) + "\n")
    out = run([METAMER, "color", "delta-e", "--pairs", path, "--json"])
    return [d["de00"] for d in json.loads(out)]


def stats(values):
    s = sorted(values)
    # p95 interpolated linearly between ranks, as metamer's verification reports it
    rank = 0.95 * (len(s) - 1)
    lo, hi = int(rank), min(int(rank) + 1, len(s) - 1)
    p95 = s[lo] + (s[hi] - s[lo]) * (rank - lo)
    return {"mean": statistics.fmean(s), "p95": p95, "max": s[-1]}


def fit_only_ti3(src, dst, labels):
    """Copies a .ti3 keeping only the data rows whose reading is not a verification patch."""
    lines = open(src).read().split("\n")
    begin = lines.index("BEGIN_DATA")
    end = lines.index("END_DATA")
    rows = lines[begin + 1 : end]
    if len(rows) != len(labels):
        sys.exit(f"{src}: {len(rows)} rows but the log has {len(labels)} readings")
    keep = [r for r, lbl in zip(rows, labels) if not lbl.startswith(VERIFICATION_PREFIXES)]
    head = [
        f"NUMBER_OF_SETS {len(keep)}" if l.startswith("NUMBER_OF_SETS") else l
        for l in lines[:begin]
    ]
    with open(dst, "w") as f:
        f.write("\n".join(head + ["BEGIN_DATA"] + keep + lines[end:]))
    return len(keep)


def one_set(out, display, model, steps, seed, algos, clut):
    d = os.path.join(out, display, f"{model}-{steps}-seed{seed}")
    if os.path.exists(d):
        shutil.rmtree(d)
    os.makedirs(os.path.dirname(d), exist_ok=True)
    t0 = time.time()
    run([METAMER, "characterize", "--display", f"virtual:{display}",
         "--instrument", f"sim:cs100a?time_scale=0&seed={seed}",
         "--model", model, "--ramp-steps", str(steps), "-o", d])
    t_metamer = time.time() - t0
    summary = json.load(open(os.path.join(d, "summary.json")))
    log = [json.loads(l) for l in open(os.path.join(d, "log.jsonl"))]
    labels = [r["label"] for r in log if r["type"] == "entry"]
    white = summary["white_xyz"]
    ver = summary["verification"]["patches"]
    measured = [p["measured_xyz"] for p in ver]
    rgb = [[c / 255 for c in p["rgb8"]] for p in ver]

    methods = {f"metamer {model}": ([p["predicted_xyz"] for p in ver], t_metamer, None)}
    runs = [(f"argyll -q{'m'} -a{a}", ["-qm", f"-a{a}"]) for a in algos]
    if clut:
        runs.append(("argyll -qh -al", ["-qh", "-al"]))
    n_fit = None
    for name, flags in runs:
        base = os.path.join(d, "argyll" + "".join(flags).replace("-", "_"))
        n_fit = fit_only_ti3(os.path.join(d, "readings.ti3"), base + ".ti3", labels)
        t0 = time.time()
        log_text = run(["colprof", "-v", *flags, "-D", name, os.path.basename(base)], cwd=d)
        t_argyll = time.time() - t0
        with open(base + ".colprof.log", "w") as f:
            f.write(log_text)
        check = [l for l in log_text.splitlines() if l.startswith("Profile check complete")]
        lut_out = run(["xicclu", "-v0", "-ff", "-iA", "-pX", base + ".icc"],
                      input="".join(f"{r:.8f} {g:.8f} {b:.8f}\n" for r, g, b in rgb))
        pred = [[float(v) for v in l.split()[:3]] for l in lut_out.strip().splitlines()]
        if len(pred) != len(rgb):
            sys.exit(f"xicclu returned {len(pred)} lines for {len(rgb)} inputs:\n{lut_out}")
        methods[name] = (pred, t_argyll, check[0] if check else None)

    records = []
    for name, (pred, secs, note) in methods.items():
        de = delta_e00([(lab(m, white), lab(p, white)) for m, p in zip(measured, pred)], d)
        if name.startswith("metamer"):
            # Our ΔE00 of metamer's prediction must be the one metamer reports (same white,
            # same formula); otherwise the comparison would not be like for like.
            for mine, p in zip(de, ver):
                if abs(mine - p["delta_e00"]) > 1e-6:
                    sys.exit(f"{d}: ΔE00 {mine} here but {p['delta_e00']} in summary.json")
        if name.startswith("metamer"):
            st, v = stats(de), summary["verification"]
            if any(abs(st[k] - v[k]) > 1e-6 for k in ("mean", "p95", "max")):
                print(f"note: {d}: p95/mean/max {st} here, {v['mean']}/{v['p95']}/{v['max']}"
                      " in summary.json", file=sys.stderr)
        records.append({
            "display": display, "plan_model": model, "ramp_steps": steps, "seed": seed,
            "fit_readings": n_fit, "fit_patches_metamer": summary["fit_patches"],
            "method": name, **stats(de), "seconds": secs, "colprof_check": note,
            "dir": d,
        })
    return records


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="target/argyll-bench")
    ap.add_argument("--display", nargs="+", default=["ips-lcd"])
    ap.add_argument("--steps", nargs="+", type=int, default=[3, 5, 9, 17])
    ap.add_argument("--model", nargs="+", default=["plcc", "matrix-lsq", "lut"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[1])
    ap.add_argument("--algos", nargs="+", default=["s", "S"])
    ap.add_argument("--clut", nargs="*", type=int, default=[],
                    help="also colprof -qh -al (Lab cLUT) on the lut sets of these ramp steps")
    ap.add_argument("--table", metavar="RESULTS_JSON", nargs="+",
                    help="only print the table of earlier runs' results.json files")
    a = ap.parse_args()
    if a.table:
        records = [r for f in a.table for r in json.load(open(f))["records"]]
        print(table(records))
        return
    os.makedirs(a.out, exist_ok=True)
    p = subprocess.run(["colprof"], capture_output=True, text=True)
    version = (p.stdout + p.stderr).splitlines()[0]
    records = []
    for display in a.display:
        for steps in a.steps:
            for model in a.model:
                for seed in a.seeds:
                    rec = one_set(a.out, display, model, steps, seed, a.algos,
                                  model == "lut" and steps in a.clut)
                    records.extend(rec)
                    for r in rec:
                        print(f"{display} {model} {steps} seed {seed} n={r['fit_readings']}"
                              f" {r['method']}: {r['mean']:.2f} / {r['p95']:.2f} /"
                              f" {r['max']:.2f}  ({r['seconds']:.1f} s)", file=sys.stderr)
    json.dump({"argyll": version, "records": records},
              open(os.path.join(a.out, "results.json"), "w"), indent=1)
    print(table(records))


def table(records):
    """Markdown: one row per display and plan, one column per method; each cell is
    ΔE00 mean / p95 / max over the 48 held-out patches, averaged over the seeds. The ramp
    plans of plcc and matrix-lsq are the same readings (same seed), so Argyll's figures are
    taken from the plcc set."""
    methods = ["metamer plcc", "metamer matrix-lsq", "metamer lut", "argyll -qm -as",
               "argyll -qm -aS", "argyll -qh -al"]
    rows = {}
    for r in records:
        grid = r["plan_model"] == "lut"
        if r["method"].startswith("argyll") and r["plan_model"] == "matrix-lsq":
            continue
        key = (r["display"], r["ramp_steps"], grid)
        rows.setdefault(key, {"n": r["fit_readings"], "m": {}})
        rows[key]["m"].setdefault(r["method"], []).append(r)
    used = [m for m in methods if any(m in v["m"] for v in rows.values())]
    out = ["| display | plan | fit readings | " + " | ".join(used) + " |",
           "| --- | --- | --- |" + " --- |" * len(used)]
    for (display, steps, grid), v in sorted(rows.items(), key=lambda kv: (kv[0][0], kv[1]["n"])):
        cells = []
        for m in used:
            rs = v["m"].get(m)
            cells.append("" if not rs else " / ".join(
                f"{statistics.fmean(r[s] for r in rs):.2f}" for s in ("mean", "p95", "max")))
        plan = f"ramps {steps}" + (f" + {steps}³ grid" if grid else "")
        out.append(f"| {display} | {plan} | {v['n']} | " + " | ".join(cells) + " |")
    return "\n".join(out)

if __name__ == "__main__":
    main()
