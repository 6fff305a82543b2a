#!/usr/bin/env python3
"""metamer's models against ArgyllCMS `colprof -qm -as` on real monitors' `.ti3` files.

Usage (from the repository root, after `cargo build --release` and `apt-get install argyll`):
  python3 benches/argyll/real_ti3.py DIR [--out target/real-ti3] [--folds 2] [--seed 1]
      [--models plcc ... shaper-matrix auto] [--sources DIR/SOURCES.txt]
DIR holds `.ti3` files as dispread / DisplayCAL write them (measured through the video-card
calibration in their CAL table; the profile describes the display as calibrated, which is
the same for both sides). For each file:
  1. `metamer fit --model shaper-matrix` on the whole file, which must read it;
  2. the patches off the cube's corners (black, primaries, secondaries, white: every fit
     needs them, so they are in every fit set) are dealt into FOLDS seeded folds; for each
     fold the file is copied without that fold's rows (the fit set) and with only them (the
     held-out set), everything else unchanged (keywords, CAL table, line endings);
  3. every metamer model is fitted on the fit set (`metamer fit`) and judged on the held-out
     set (`metamer verify --json`, CIELAB relative to the profile's white, which is the fit
     set's measured white);
  4. `colprof -qm -as` profiles the same fit set (run as an external program), `xicclu -ff
     -iA -pX` looks the held-out drive values up (display-absolute XYZ in cd/m²) and ΔE00
     comes from `metamer color delta-e`, relative to the same white as metamer's.
The held-out ΔE00 of each method is pooled over the folds (every non-corner patch is judged
once).

With --ramps-only the split is not random: the fit set is what a ramp-only plan measures
(black, white and every single-channel patch, all their repeats), and the held-out set is
every mixed patch of the file (greys, secondaries, the rest), judged once. The script checks that the held-out XYZ it parses equal what `metamer verify` read
for its worst patches, so both sides are judged against the same numbers. Prints a Markdown
table; OUT/results.json keeps every fold's figures.
"""

import argparse
import json
import os
import random
import shutil
import sys

sys.path.insert(0, os.path.dirname(__file__))
from compare import METAMER, delta_e00, lab, run, stats  # noqa: E402

MODELS = ["plcc", "plcc-gamma", "plvc", "gog", "gogo", "matrix-lsq", "shaper-matrix", "lut",
          "auto"]


def tokens(line):
    """CGATS tokens: whitespace (spaces or tabs) separated, "quoted strings" kept whole."""
    out, cur, quoted = [], "", False
    for ch in line:
        if ch == '"':
            quoted = not quoted
            cur += ch
        elif ch.isspace() and not quoted:
            if cur:
                out.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        out.append(cur)
    return out


class Ti3:
    """The first table of a .ti3: its lines (with their endings), where the data rows are,
    and each row's drive values (0–1) and absolute XYZ."""

    def __init__(self, path):
        self.lines = open(path, newline="").read().splitlines(keepends=True)
        bare = [tokens(l) for l in self.lines]
        first = lambda i: bare[i][0] if bare[i] else ""  # noqa: E731
        fmt = next(i for i in range(len(bare)) if first(i) == "BEGIN_DATA_FORMAT")
        fields = []
        i = fmt + 1
        while first(i) != "END_DATA_FORMAT":
            fields += bare[i]
            i += 1
        self.begin = next(j for j in range(i, len(bare)) if first(j) == "BEGIN_DATA")
        self.end = next(j for j in range(self.begin, len(bare)) if first(j) == "END_DATA")
        self.sets_line = next(j for j in range(self.begin) if first(j) == "NUMBER_OF_SETS")
        keywords = {t[0]: " ".join(t[1:]).strip('"') for t in bare[: self.begin] if t}
        normalised = keywords.get("NORMALIZED_TO_Y_100", "YES").upper() != "NO"
        lum = keywords.get("LUMINANCE_XYZ_CDM2")
        scale = float(lum.split()[1]) / 100 if (normalised and lum) else 1.0
        col = {f: k for k, f in enumerate(fields)}
        self.rgb, self.xyz = [], []
        for j in range(self.begin + 1, self.end):
            t = bare[j]
            self.rgb.append([float(t[col[f]]) / 100 for f in ("RGB_R", "RGB_G", "RGB_B")])
            self.xyz.append([float(t[col[f]]) * scale for f in ("XYZ_X", "XYZ_Y", "XYZ_Z")])

    def write(self, path, rows):
        """A copy holding only the data rows `rows` (indices into the table)."""
        eol = self.lines[self.sets_line][len(self.lines[self.sets_line].rstrip("\r\n")):]
        head = list(self.lines[: self.begin + 1])
        head[self.sets_line] = f"NUMBER_OF_SETS {len(rows)}{eol}"
        data = [self.lines[self.begin + 1 + r] for r in rows]
        with open(path, "w", newline="") as f:
            f.write("".join(head + data + self.lines[self.end:]))


def corner(rgb):
    return all(v <= 1e-6 or v >= 1 - 1e-6 for v in rgb)


def single_channel(rgb):
    """Black, white or a patch with one channel on: what a ramp-only plan measures."""
    on = [v > 1e-6 for v in rgb]
    return sum(on) <= 1 or all(v >= 1 - 1e-6 for v in rgb)


def one_file(path, out, folds, seed, models, ramps_only=False):
    name = os.path.splitext(os.path.basename(path))[0]
    d = os.path.join(out, name)
    if os.path.exists(d):
        shutil.rmtree(d)
    os.makedirs(d)
    ti3 = Ti3(path)
    # metamer must read the whole file as it is.
    run([METAMER, "fit", "--model", "shaper-matrix", "--measurements", path,
         "-o", os.path.join(d, "whole.json")])
    fixed = [i for i, c in enumerate(ti3.rgb) if corner(c)]
    rest = [i for i, c in enumerate(ti3.rgb) if not corner(c)]
    random.Random(seed).shuffle(rest)
    if ramps_only:
        folds = 1
    records = []
    for k in range(folds):
        if ramps_only:
            fit = [i for i, c in enumerate(ti3.rgb) if single_channel(c)]
            held = [i for i, c in enumerate(ti3.rgb) if not single_channel(c)]
        else:
            held = sorted(rest[k::folds])
            fit = sorted(fixed + [i for i in rest if i not in set(held)])
        fd = os.path.join(d, f"fold{k}")
        os.makedirs(fd)
        ti3.write(os.path.join(fd, "fit.ti3"), fit)
        ti3.write(os.path.join(fd, "heldout.ti3"), held)
        rec = {"file": name, "fold": k, "fit": len(fit), "held_out": len(held), "methods": {}}
        white = None
        for model in models:
            prof = os.path.join(fd, f"{model}.json")
            p = run_soft([METAMER, "fit", "--model", model, "--measurements",
                          os.path.join(fd, "fit.ti3"), "-o", prof])
            if p is None:
                rec["methods"][model] = None
                continue
            chose = [l.split()[1].rstrip(":") for l in p.splitlines() if l.startswith("chose ")]
            v = json.loads(run([METAMER, "verify", "--profile", prof, "--measurements",
                                os.path.join(fd, "heldout.ti3"), "--json"]))
            for w in v["worst"]:
                mine = ti3.xyz[held[w["index"] - 1]]
                if any(abs(a - b) > 1e-6 * max(1.0, abs(b)) for a, b in zip(mine, w["measured_xyz"])):
                    sys.exit(f"{path}: held-out patch {w['index']} is {mine} here, "
                             f"{w['measured_xyz']} for metamer")
            white = json.load(open(prof))["white_xyz"]
            rec["methods"][model] = {"mean": v["de00"]["mean"], "p95": v["de00"]["p95"],
                                     "max": v["de00"]["max"], "n": v["patches"],
                                     "chose": chose[0] if chose else None}
        run(["colprof", "-qm", "-as", "-D", "as", "fit"], cwd=fd)
        rgb = [ti3.rgb[i] for i in held]
        out_lu = run(["xicclu", "-v0", "-ff", "-iA", "-pX", os.path.join(fd, "fit.icc")],
                     input="".join(f"{r:.8f} {g:.8f} {b:.8f}\n" for r, g, b in rgb))
        pred = [[float(x) for x in l.split()[:3]] for l in out_lu.strip().splitlines()]
        if len(pred) != len(rgb):
            sys.exit(f"xicclu returned {len(pred)} lines for {len(rgb)} inputs")
        de = delta_e00([(lab(ti3.xyz[i], white), lab(q, white)) for i, q in zip(held, pred)], fd)
        rec["methods"]["colprof -as"] = {**stats(de), "n": len(de), "chose": None}
        records.append(rec)
        print(f"{name} fold {k}: " + ", ".join(
            f"{m} {r['mean']:.3f}" if r else f"{m} -" for m, r in rec["methods"].items()),
            file=sys.stderr)
    return len(ti3.rgb), records


def run_soft(cmd):
    """Runs a fit that may be refused (a model that needs ramps the set lacks): None then."""
    import subprocess
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.stdout if p.returncode == 0 else None


def tally(records, models):
    """One line: on how many files the best metamer model is at or below colprof -as, and
    auto's pick is at or below it and within 5 % of the best model (means pooled over folds)."""
    by_file = {}
    for r in records:
        by_file.setdefault(r["file"], []).append(r)
    counts = {"best <= colprof": 0, "auto <= colprof": 0, "auto within 5 %": 0}
    n = 0
    for recs in by_file.values():
        def pooled(m):
            got = [r["methods"].get(m) for r in recs]
            if any(g is None for g in got):
                return None
            return sum(g["mean"] * g["n"] for g in got) / sum(g["n"] for g in got)
        fitted = [v for v in (pooled(m) for m in models) if v is not None]
        auto, colprof = pooled("auto"), pooled("colprof -as")
        if not fitted or auto is None or colprof is None:
            continue
        n += 1
        best = min(fitted)
        counts["best <= colprof"] += best <= colprof
        counts["auto <= colprof"] += auto <= colprof
        counts["auto within 5 %"] += auto <= 1.05 * best
    if n == 0:
        return ""
    return f"Of {n} files: " + "; ".join(f"{k} on {v}" for k, v in counts.items()) + "."


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--out", default="target/real-ti3")
    ap.add_argument("--folds", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--models", nargs="+", default=MODELS)
    ap.add_argument("--sources", help="tab-separated: file name, where it came from")
    ap.add_argument("--ramps-only", action="store_true",
                    help="fit on black, white and the single-channel patches; judge on the rest")
    a = ap.parse_args()
    if shutil.which("colprof") is None:
        sys.exit("ArgyllCMS colprof is not installed (apt-get install argyll)")
    sources = {}
    if a.sources:
        for line in open(a.sources):
            if "\t" in line:
                f, src = line.rstrip("\n").split("\t", 1)
                sources[f] = src
    os.makedirs(a.out, exist_ok=True)
    methods = ["colprof -as"] + a.models
    rows, everything = [], []
    for f in sorted(os.listdir(a.dir)):
        if not f.endswith(".ti3"):
            continue
        n, records = one_file(os.path.join(a.dir, f), a.out, a.folds, a.seed, a.models,
                              a.ramps_only)
        everything += records
        cells = []
        for m in methods:
            got = [r["methods"].get(m) for r in records]
            if any(g is None for g in got):
                cells.append("—")
                continue
            total = sum(g["n"] for g in got)
            mean = sum(g["mean"] * g["n"] for g in got) / total
            chose = sorted({g["chose"] for g in got if g["chose"]})
            cells.append(f"{mean:.3f}" + (f" ({', '.join(chose)})" if chose else ""))
        sizes = f"{records[0]['fit']} / {records[0]['held_out']}" if a.ramps_only else str(n)
        rows.append(f"| {f} | {sizes} | " + " | ".join(cells) + " |")
    json.dump(everything, open(os.path.join(a.out, "results.json"), "w"), indent=1)
    head = "fit / held-out" if a.ramps_only else "patches"
    print(f"| file | {head} | " + " | ".join(methods) + " |")
    print("| --- | --- |" + " --- |" * len(methods))
    print("\n".join(rows))
    summary = tally(everything, [m for m in a.models if m != "auto"])
    if summary:
        print()
        print(summary)
    if sources:
        print()
        for f in sorted(sources):
            print(f"- `{f}`: {sources[f]}")


if __name__ == "__main__":
    main()
