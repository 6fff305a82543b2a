#!/usr/bin/env bash
# Reproduces the figures of benches/mitsuba/README.md: `metamer render spots` and the Mitsuba 3
# cross-check (both wavelength-sampling modes), alternating, each timed, the machine's load
# recorded before each run. From the repository root, after `cargo build --release`:
#   benches/mitsuba/run.sh PYTHON [ROUNDS] [OUTDIR]
# PYTHON: an interpreter with `mitsuba` and `numpy` (see README.md). METAMER overrides the
# binary (default ./target/release/metamer).
set -euo pipefail
PY=${1:?usage: run.sh PYTHON [ROUNDS] [OUTDIR]}
ROUNDS=${2:-2}
OUT=${3:-target/mitsuba-bench}
METAMER=${METAMER:-./target/release/metamer}
[ -x "$METAMER" ] || { echo "no $METAMER: run cargo build --release first" >&2; exit 2; }
mkdir -p "$OUT"
for r in $(seq 1 "$ROUNDS"); do
    echo "== round $r: metamer render spots"; uptime
    /usr/bin/time -f "metamer wall %e s, user %U s, sys %S s" \
        nice -n 10 "$METAMER" render spots data/scenes/validation-box-led-rgb1.json \
        --method path --target-de 0.1 --seed "$r" --json > "$OUT/metamer_$r.json"
    for wl in cmf light; do
        echo "== round $r: Mitsuba, wavelengths $wl"; uptime
        /usr/bin/time -f "mitsuba ($wl) wall %e s, user %U s, sys %S s" \
            nice -n 10 "$PY" benches/mitsuba/validation_box.py --target-de 0.1 --seed "$r" \
            --wavelengths "$wl" --metamer-json "$OUT/metamer_$r.json" \
            --out "$OUT/mitsuba_${wl}_$r.json" > "$OUT/mitsuba_${wl}_$r.log"
        grep -E "^white|^Mitsuba:|ΔE\*ab, metamer" "$OUT/mitsuba_${wl}_$r.log"
    done
done
uptime
