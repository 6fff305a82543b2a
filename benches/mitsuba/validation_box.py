#!/usr/bin/env python3
"""Cross-check of metamer's spot meter against Mitsuba 3 on the validation box.

A side benchmark, not part of the Rust build or CI (see README.md in this directory).

The scene is read from metamer's own scene file (data/scenes/validation-box-led-rgb1.json) and the CSV
spectra it names, and rebuilt in Mitsuba:

* every rectangle is a Mitsuba `rectangle` whose local frame maps onto corner/edge_u/edge_v,
  so its front side (normal edge_u x edge_v) is the side metamer treats as the inside face;
  Lambertian surfaces are `diffuse` BSDFs (one-sided in Mitsuba, black from behind);
* the emitter is split into its rows x cols tiles, each an `area` emitter with radiance
  s*S(lambda)*gain on a black `diffuse` BSDF (the scene's emitter reflectance is 0 by
  default); s is fixed by the contract: 683 * sum_{380..780 nm, 1 nm} s*S*ybar = luminance;
* spectra are `irregular` spectra holding the tabulated values (linear interpolation, zero
  outside the table, which is Mitsuba's behaviour and the contract's default); tables marked
  "outside": "hold_ends" get their end values repeated at 360 and 830 nm, the ends of
  Mitsuba's spectral range.

The meter: per patch, a `perspective` sensor at the pinhole aimed at the patch centre with a
1 deg x 1 deg field (square, not the contract's 1 deg cone: the patch is uniform and both
footprints are well inside the 40 mm patch, so the means agree to second order in the small
illumination gradient) and a 16 x 16 `specfilm` with a box filter. The film's three channels
have the CIE 1931 2 deg colour-matching functions of data/cie1931_2deg_cmf_1nm.csv, restricted
to 380-780 nm, as spectral response functions. Mitsuba's specfilm returns the unnormalised
integral of radiance times the response function (checked with --check-emitter: the emitter
seen head-on reads 100 cd/m2 x tile gain), so a pixel times K_m = 683 lm/W is absolute XYZ in
cd/m2. The reading is the mean of the 256 pixels; its covariance is estimated from the spread
of the 256 independent per-pixel estimates (slightly conservative: the little real variation
of radiance across the field counts as noise).

Convergence mirrors `metamer render spots`: a reference white (a perfect white diffuser in place
of patch 19) refined to a ΔE*ab half-width of target/3, then each patch rendered in batches,
new seed per batch, until the 95 % half-width of its ΔE*ab (1.96 x RMS of the ΔE*ab of the mean,
propagated from the XYZ covariance through the CIELAB Jacobian) is below the target.
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np

K_M = 683.0  # lm/W, photopic maximum luminous efficacy (contract, paper Eq. 8)
LAMBDA_MIN, LAMBDA_MAX = 380, 780  # integration range of the contract
MI_MIN, MI_MAX = 360.0, 830.0  # Mitsuba 3's spectral range (MI_CIE_MIN/MAX in spectrum.h)


# ----------------------------------------------------------------------------- data


def read_csv_table(path):
    """A data/*.csv table: comment line(s) starting with '#', a header, numeric rows."""
    rows = []
    header = None
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if header is None:
                header = line.split(",")
                continue
            rows.append([float(x) for x in line.split(",")])
    if header is None or not rows:
        raise SystemExit(f"{path}: no table found")
    return header, np.array(rows)


class Spectrum:
    """A tabulated spectrum and what it does outside its table."""

    def __init__(self, nm, values, hold_ends=False):
        self.nm = np.asarray(nm, float)
        self.values = np.asarray(values, float)
        self.hold_ends = hold_ends

    def at(self, nm):
        if self.hold_ends:
            return np.interp(nm, self.nm, self.values)
        return np.interp(nm, self.nm, self.values, left=0.0, right=0.0)

    def scaled(self, k):
        return Spectrum(self.nm, self.values * k, self.hold_ends)

    def mitsuba(self):
        if self.hold_ends and np.all(self.values == self.values[0]):
            # Flat (a grey frame, the perfect white, a black emitter surface); Mitsuba's
            # irregular spectrum refuses all-zero tables.
            return {"type": "uniform", "value": float(self.values[0])}
        nm, v = list(self.nm), list(self.values)
        if self.hold_ends:
            if nm[0] > MI_MIN:
                nm.insert(0, MI_MIN)
                v.insert(0, v[0])
            if nm[-1] < MI_MAX:
                nm.append(MI_MAX)
                v.append(v[-1])
        return {
            "type": "irregular",
            "wavelengths": ", ".join(repr(float(x)) for x in nm),
            "values": ", ".join(repr(float(x)) for x in v),
        }


def load_spectrum(ref, scene_dir, what):
    if isinstance(ref, (int, float)):
        # A flat value: one constant over Mitsuba's whole range.
        return Spectrum([MI_MIN, MI_MAX], [float(ref)] * 2, hold_ends=True)
    outside = ref.get("outside", "zero")
    if outside not in ("zero", "hold_ends"):
        raise SystemExit(f"{what}: unknown 'outside': {outside!r}")
    if "nm" in ref:
        return Spectrum(
            np.asarray(ref["nm"], float),
            np.asarray(ref["values"], float),
            hold_ends=(outside == "hold_ends"),
        )
    path = os.path.normpath(os.path.join(scene_dir, ref["file"]))
    header, table = read_csv_table(path)
    col = int(ref.get("column", 1))
    if not 1 <= col < table.shape[1]:
        raise SystemExit(f"{what}: column {col} not in {path} ({header})")
    outside = ref.get("outside", "zero")
    if outside not in ("zero", "hold_ends"):
        raise SystemExit(f"{what}: unknown 'outside': {outside!r}")
    return Spectrum(table[:, 0], table[:, col], hold_ends=(outside == "hold_ends"))


def load_cmf(data_dir):
    _, t = read_csv_table(os.path.join(data_dir, "cie1931_2deg_cmf_1nm.csv"))
    sel = (t[:, 0] >= LAMBDA_MIN) & (t[:, 0] <= LAMBDA_MAX)
    return t[sel, 0], t[sel, 1:4]


# ----------------------------------------------------------------------------- colour


def xyz_of(spectrum, cmf_nm, cmf):
    """Contract's absolute XYZ (cd/m2) of a radiance: 683 * sum over 380..780 nm at 1 nm."""
    return K_M * (spectrum.at(cmf_nm)[:, None] * cmf).sum(axis=0)


def _f(t):
    d = 6.0 / 29.0
    return np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)


def lab(xyz, white):
    """CIELAB 1976 (CIE 15:2018 §8.2.1)."""
    fx, fy, fz = (_f(np.asarray(xyz[i]) / white[i]) for i in range(3))
    return np.array([116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)])


def lab_jacobian(xyz, white):
    """dLab/dXYZ by central differences (the white held exact, as metamer does)."""
    j = np.zeros((3, 3))
    for i in range(3):
        h = 1e-6 * max(abs(xyz[i]), 1e-9)
        a, b = np.array(xyz, float), np.array(xyz, float)
        a[i] += h
        b[i] -= h
        j[:, i] = (lab(a, white) - lab(b, white)) / (2 * h)
    return j


def de_ci95(mean, cov_of_mean, white):
    """95 % half-width of ΔE*ab of the mean: 1.96 * sqrt(trace(J Σ J^T))."""
    j = lab_jacobian(mean, white)
    return 1.96 * math.sqrt(max(np.trace(j @ cov_of_mean @ j.T), 0.0))


def de76(a, b):
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)))


# ----------------------------------------------------------------------------- scene


def rect_to_world(mi, corner, eu, ev):
    """Mitsuba's rectangle is [-1,1]^2 in local xy with normal +z; map x->edge_u, y->edge_v,
    z->unit(edge_u x edge_v) so that the front face is the one metamer's normal points out of."""
    c, u, v = (np.asarray(x, float) for x in (corner, eu, ev))
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    o = c + 0.5 * (u + v)
    m = np.array(
        [
            [u[0] / 2, v[0] / 2, n[0], o[0]],
            [u[1] / 2, v[1] / 2, n[1], o[1]],
            [u[2] / 2, v[2] / 2, n[2], o[2]],
            [0, 0, 0, 1],
        ]
    )
    return mi.ScalarTransform4f(m.tolist())


class Box:
    """The validation box as read from metamer's scene file."""

    def __init__(self, scene_path, wavelengths="cmf"):
        self.wavelengths = wavelengths
        self.path = os.path.abspath(scene_path)
        self.dir = os.path.dirname(self.path)
        with open(self.path) as f:
            self.json = json.load(f)
        self.data_dir = os.path.normpath(os.path.join(self.dir, ".."))
        self.cmf_nm, self.cmf = load_cmf(self.data_dir)
        self.surfaces = []
        for s in self.json["surfaces"]:
            self.surfaces.append(
                dict(
                    name=s["name"],
                    corner=s["corner"],
                    eu=s["edge_u"],
                    ev=s["edge_v"],
                    refl=load_spectrum(s["reflectance"], self.dir, s["name"]),
                    patch=s.get("patch"),
                )
            )
        if len(self.json["emitters"]) != 1:
            raise SystemExit("expected exactly one emitter")
        e = self.json["emitters"][0]
        kind = e.get("distribution", {}).get("kind", "lambertian")
        if kind != "lambertian":
            # Mitsuba 3's `area` emitter radiates the same radiance in every direction; a
            # cos_power or C-gamma (measured) distribution has no equivalent without a
            # custom plugin, so such a scene is not compared at all rather than wrongly.
            raise SystemExit(
                f"the emitter's distribution is {kind!r}: Mitsuba 3's area emitter is "
                "Lambertian only, so this scene cannot be cross-checked here"
            )
        self.emitter = e
        self.gains = {(t["row"], t["col"]): t.get("gain", 1.0) for t in e["tiles"]}
        if len(self.gains) != e["rows"] * e["cols"]:
            raise SystemExit("emitter: tile gains do not cover the grid")
        with_spectra = [t for t in e["tiles"] if "spectrum" in t]
        if with_spectra:
            # Absolute per-tile spectral radiance (W/sr/m2/nm along the normal) times gain.
            if len(with_spectra) != len(e["tiles"]):
                raise SystemExit("emitter: some tiles have a spectrum and some do not")
            self.tile_spectra = {
                (t["row"], t["col"]): load_spectrum(
                    t["spectrum"], self.dir, f"tile ({t['row']}, {t['col']}) spectrum"
                )
                for t in e["tiles"]
            }
            self.scale = 1.0
            self.spectrum = None
        else:
            self.tile_spectra = None
            self.spectrum = load_spectrum(e["spectrum"], self.dir, "emitter spectrum")
            ybar_sum = (self.spectrum.at(self.cmf_nm) * self.cmf[:, 1]).sum()
            self.scale = e["luminance_cd_m2"] / (K_M * ybar_sum)
        self.emitter_refl = (
            load_spectrum(e["reflectance"], self.dir, "emitter reflectance")
            if e.get("reflectance") is not None
            else Spectrum([MI_MIN, MI_MAX], [0.0, 0.0], hold_ends=True)
        )
        cam = self.json["camera"]
        self.pinhole = np.asarray(cam["position"], float)
        self.acceptance_deg = float(self.json["meter"]["acceptance_deg"])

    def tile_rect(self, row, col):
        e = self.emitter
        c = np.asarray(e["corner"], float)
        u = np.asarray(e["edge_u"], float) / e["cols"]
        v = np.asarray(e["edge_v"], float) / e["rows"]
        return c + col * u + row * v, u, v

    def patch_centre(self, k):
        for s in self.surfaces:
            if s["patch"] == k:
                return (
                    np.asarray(s["corner"], float)
                    + 0.5 * np.asarray(s["eu"], float)
                    + 0.5 * np.asarray(s["ev"], float)
                )
        raise SystemExit(f"patch {k} not in the scene")

    def tile_luminance(self, row, col):
        """Luminance along the normal of one tile (cd/m2), as metamer computes it."""
        s = self.tile_radiance_spectrum(row, col)
        return K_M * (s.at(self.cmf_nm) * self.cmf[:, 1]).sum()

    def channels(self):
        """Spectral response functions of the film's X, Y, Z channels."""
        if self.wavelengths == "light" and self.spectrum is None:
            raise SystemExit(
                "--wavelengths light needs one light spectrum; this scene's tiles have their own"
            )
        if self.wavelengths == "light":
            w = self.spectrum.at(self.cmf_nm)[:, None] * self.cmf
        else:
            w = self.cmf
        return [Spectrum(self.cmf_nm, np.maximum(w[:, i], 0.0)) for i in range(3)]

    def tile_radiance_spectrum(self, row, col):
        """The tile's absolute spectral radiance (gain included)."""
        g = self.gains[(row, col)]
        if self.tile_spectra is not None:
            return self.tile_spectra[(row, col)].scaled(g)
        return self.spectrum.scaled(self.scale * g)

    def tile_radiance(self, row, col):
        if self.wavelengths == "light":
            self.channels()  # refuses per-tile spectra
            # The light's spectrum S(lambda) lives in the film's channels instead (see
            # --wavelengths); the tiles emit the flat s * gain.
            g = self.gains[(row, col)]
            return Spectrum([MI_MIN, MI_MAX], [self.scale * g] * 2, hold_ends=True)
        return self.tile_radiance_spectrum(row, col)

    def mitsuba_dict(self, mi, white_patch=None, max_depth=-1, rr_depth=5):
        d = {
            "type": "scene",
            "integrator": {
                "type": "path",
                "max_depth": max_depth,
                "rr_depth": rr_depth,
                # 16x16 film in 8x8 blocks: 4 blocks, so both cores of this machine work.
                "block_size": 8,
            },
        }
        for i, s in enumerate(self.surfaces):
            refl = s["refl"]
            if white_patch is not None and s["patch"] == white_patch:
                refl = Spectrum([MI_MIN, MI_MAX], [1.0, 1.0], hold_ends=True)
            d[f"surface_{i:02d}"] = {
                "type": "rectangle",
                "to_world": rect_to_world(mi, s["corner"], s["eu"], s["ev"]),
                "bsdf": {"type": "diffuse", "reflectance": refl.mitsuba()},
            }
        for (row, col), g in sorted(self.gains.items()):
            c, u, v = self.tile_rect(row, col)
            d[f"tile_{row}_{col}"] = {
                "type": "rectangle",
                "to_world": rect_to_world(mi, c, u, v),
                "emitter": {
                    "type": "area",
                    "radiance": self.tile_radiance(row, col).mitsuba(),
                },
                "bsdf": {"type": "diffuse", "reflectance": self.emitter_refl.mitsuba()},
            }
        return d

    def sensor(self, mi, origin, target, up=(0, 1, 0), res=16, spp=16):
        film = {
            "type": "specfilm",
            "width": res,
            "height": res,
            "rfilter": {"type": "box"},
        }
        # Channel names sort in X, Y, Z order; the order is checked on the emitter.
        for ch, srf in zip("XYZ", self.channels()):
            film[ch] = srf.mitsuba()
        return mi.load_dict(
            {
                "type": "perspective",
                "fov": self.acceptance_deg,
                "fov_axis": "x",
                "near_clip": 1e-3,
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[float(x) for x in origin],
                    target=[float(x) for x in target],
                    up=list(up),
                ),
                "film": film,
                "sampler": {"type": "independent", "sample_count": spp},
            }
        )


# ----------------------------------------------------------------------------- rendering


class Meter:
    """Accumulates per-pixel estimates of one reading over batches."""

    def __init__(self, mi, scene, sensor, seed_base):
        self.mi, self.scene, self.sensor = mi, scene, sensor
        self.seed_base = seed_base
        self.sum = None  # per-pixel sum of XYZ over batches, weighted by spp
        self.spp = 0
        self.batches = 0
        self.pixels = 0

    def add(self, spp):
        img = self.mi.render(
            self.scene, sensor=self.sensor, spp=int(spp), seed=self.seed_base + self.batches
        )
        px = np.array(img, dtype=np.float64).reshape(-1, 3) * K_M
        self.sum = px * spp if self.sum is None else self.sum + px * spp
        self.spp += int(spp)
        self.batches += 1
        self.pixels = px.shape[0]

    @property
    def samples(self):
        return self.spp * self.pixels

    def mean(self):
        return (self.sum / self.spp).mean(axis=0)

    def cov_of_mean(self):
        px = self.sum / self.spp
        return np.cov(px, rowvar=False) / px.shape[0]

    def converge(self, white, target, first_spp, log=None, max_seconds=3600):
        start = time.perf_counter()
        if self.spp == 0:
            self.add(first_spp)
        while True:
            w = self.mean() if white is None else white
            hw = de_ci95(self.mean(), self.cov_of_mean(), w)
            if hw < target or time.perf_counter() - start > max_seconds:
                return hw
            # 1/sqrt(N) law, 10 % margin, at most doubling per step (as metamer does).
            need = self.spp * (hw / target) ** 2 * 1.1 - self.spp
            add = int(min(max(need, first_spp), self.spp))
            if log:
                log(f"    hw {hw:.3f} after {self.spp} spp, +{add}")
            self.add(add)


def check_emitter(mi, box, args):
    """The emitter head-on, one tile at a time: must read luminance x gain."""
    scene = mi.load_dict(box.mitsuba_dict(mi, max_depth=args.max_depth))
    rows = []
    worst = 0.0
    for (row, col), g in sorted(box.gains.items()):
        c, u, v = box.tile_rect(row, col)
        centre = c + 0.5 * (u + v)
        n = np.cross(u, v)
        n /= np.linalg.norm(n)
        sensor = box.sensor(mi, centre + 0.2 * n, centre, up=(0, 0, 1), res=4)
        m = Meter(mi, scene, sensor, seed_base=7_000_000 + 100 * row + col)
        m.add(args.check_spp)
        got = m.mean()
        exp = xyz_of(box.tile_radiance_spectrum(row, col), box.cmf_nm, box.cmf)
        rel = got / exp - 1
        worst = max(worst, float(np.abs(rel).max()))
        rows.append(dict(row=row, col=col, gain=g, XYZ=got.tolist(), expected=exp.tolist()))
        print(
            f"  tile ({row},{col}) gain {g:.2f}: Y {got[1]:8.4f} cd/m2 (expected {exp[1]:8.4f}), "
            f"X/Y/Z rel. error {rel[0]:+.1e} {rel[1]:+.1e} {rel[2]:+.1e}"
        )
    print(f"  emitter check: worst relative error {worst:.2e} ({args.check_spp} spp x 16 px per tile)")

    if box.wavelengths != "cmf":
        return dict(tiles=rows, worst_relative_error=worst, spp=args.check_spp)
    # Mitsuba's own XYZ output (hdrfilm, pixel_format "xyz") on the centre tile, for the
    # record: it divides by the integral of its own ybar table (MI_CIE_Y_NORMALIZATION in
    # include/mitsuba/core/spectrum.h) and uses its 5 nm CIE 1931 table over 360-830 nm.
    row, col = box.emitter["rows"] // 2, box.emitter["cols"] // 2
    c, u, v = box.tile_rect(row, col)
    centre = c + 0.5 * (u + v)
    n = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    sensor = mi.load_dict(
        {
            "type": "perspective",
            "fov": box.acceptance_deg,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=(centre + 0.2 * n).tolist(), target=centre.tolist(), up=[0, 0, 1]
            ),
            "film": {"type": "hdrfilm", "width": 4, "height": 4, "pixel_format": "xyz",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": args.check_spp},
        }
    )
    img = np.array(mi.render(scene, sensor=sensor, seed=99), dtype=np.float64).reshape(-1, 3)
    y_builtin = img[:, 1].mean()
    exp_y = expected_rel[1] * box.gains[(row, col)]
    k = exp_y / (K_M * y_builtin)
    print(
        f"  built-in xyz film, tile ({row},{col}): Y = {y_builtin:.6e}; luminance / (683 Y) = {k:.2f} "
        f"(Mitsuba's 1/MI_CIE_Y_NORMALIZATION = 106.75)"
    )
    return dict(tiles=rows, worst_relative_error=worst, spp=args.check_spp,
                builtin_xyz_centre_tile_Y=y_builtin, builtin_xyz_implied_norm=k)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.normpath(os.path.join(here, "..", ".."))
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scene", default=os.path.join(root, "data/scenes/validation-box-led-rgb1.json"))
    p.add_argument("--variant", default="scalar_spectral")
    p.add_argument("--target-de", type=float, default=0.1)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--first-spp", type=int, default=16, help="first batch, per pixel (256 px)")
    p.add_argument("--max-depth", type=int, default=-1, help="Mitsuba default: -1 (unbounded)")
    p.add_argument("--rr-depth", type=int, default=5, help="Mitsuba default: 5")
    p.add_argument(
        "--wavelengths",
        choices=["cmf", "light"],
        default="cmf",
        help="cmf: film channels are the CMFs, Mitsuba samples wavelengths by their sum, the "
        "emitter carries S(lambda) (plain Mitsuba). light: the same integral rewritten so that "
        "Mitsuba samples wavelengths by S(lambda) x (xbar+ybar+zbar) as metamer does: the film "
        "channels are S x CMF and the tiles emit a flat s x gain. Exact because the scene has "
        "one emission spectrum, so every radiance is S(lambda) times a transport factor.",
    )
    p.add_argument("--metamer-json", help="output of `metamer render spots ... --json`")
    p.add_argument("--check-emitter", action="store_true", help="only the head-on emitter check")
    p.add_argument("--check-spp", type=int, default=4096)
    p.add_argument("--out", help="write the results as JSON here")
    p.add_argument("--verbose", action="store_true")
    args = p.parse_args()

    t_import = time.perf_counter()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    box = Box(args.scene, args.wavelengths)
    print(
        f"Mitsuba {mi.__version__}, variant {args.variant}, threads {dr.thread_count()}, "
        f"wavelength sampling: {args.wavelengths}"
    )
    if box.spectrum is not None:
        lum = box.emitter["luminance_cd_m2"]
        print(f"emitter scale s = {box.scale:.6e} (683 * sum s*S*ybar = {lum} cd/m2)")
    else:
        print("emitter: absolute spectral radiance per tile")

    if args.check_emitter:
        res = check_emitter(mi, box, args)
        if args.out:
            with open(args.out, "w") as f:
                json.dump(
                    dict(mitsuba=mi.__version__, variant=args.variant,
                         wavelengths=args.wavelengths, emitter_check=res),
                    f,
                    indent=1,
                )
        return

    log = print if args.verbose else None
    t0 = time.perf_counter()
    scene = mi.load_dict(box.mitsuba_dict(mi, max_depth=args.max_depth, rr_depth=args.rr_depth))
    wscene = mi.load_dict(
        box.mitsuba_dict(mi, white_patch=19, max_depth=args.max_depth, rr_depth=args.rr_depth)
    )
    t_load = time.perf_counter() - t0

    # Reference white: perfect diffuser in place of patch 19, to a third of the target.
    t1 = time.perf_counter()
    wm = Meter(mi, wscene, box.sensor(mi, box.pinhole, box.patch_centre(19)), args.seed * 10_000_000)
    w_hw = wm.converge(None, args.target_de / 3, args.first_spp, log)
    white = wm.mean()
    t_white = time.perf_counter() - t1
    print(f"white XYZ {white.round(4).tolist()} (half-width {w_hw:.3f}, {wm.samples} samples, {t_white:.1f} s)")

    patches = []
    for k in range(1, 25):
        tk = time.perf_counter()
        sensor = box.sensor(mi, box.pinhole, box.patch_centre(k))
        m = Meter(mi, scene, sensor, args.seed * 10_000_000 + k * 100_000)
        hw = m.converge(white, args.target_de, args.first_spp, log)
        xyz = m.mean()
        patches.append(
            dict(
                patch=k,
                XYZ=xyz.tolist(),
                XYZ_stderr=np.sqrt(np.diag(m.cov_of_mean())).tolist(),
                cov_of_mean=m.cov_of_mean().tolist(),
                Lab=lab(xyz, white).tolist(),
                de_ci95=hw,
                spp_per_pixel=m.spp,
                samples=m.samples,
                batches=m.batches,
                seconds=time.perf_counter() - tk,
            )
        )
        print(
            f"patch {k:2d}: XYZ {xyz[0]:8.4f} {xyz[1]:8.4f} {xyz[2]:8.4f}  hw {hw:.3f}  "
            f"{m.samples:8d} samples ({m.spp} spp x {m.pixels} px)  {patches[-1]['seconds']:.1f} s"
        )
    t_render = time.perf_counter() - t1
    print(
        f"Mitsuba: scene load {t_load:.1f} s, white + 24 patches {t_render:.1f} s, "
        f"{sum(p['samples'] for p in patches) + wm.samples} samples in all "
        f"(process so far {time.perf_counter() - t_import:.1f} s)"
    )

    result = dict(
        mitsuba=mi.__version__,
        variant=args.variant,
        threads=dr.thread_count(),
        settings=dict(
            integrator="path",
            max_depth=args.max_depth,
            rr_depth=args.rr_depth,
            sampler="independent",
            wavelengths=args.wavelengths,
            sensor="perspective, 1 deg x 1 deg, 16x16 specfilm (CIE 1931 2 deg, 380-780 nm), box filter",
            target_de=args.target_de,
            seed=args.seed,
        ),
        white=white.tolist(),
        white_de_ci95=w_hw,
        white_samples=wm.samples,
        seconds_load=t_load,
        seconds_white=t_white,
        seconds_render=t_render,
        patches=patches,
    )

    if args.metamer_json:
        with open(args.metamer_json) as f:
            mm = json.load(f)
        mw = np.asarray(mm["white"])
        print(f"white: metamer {np.round(mw, 4).tolist()}, ΔE*ab(Mitsuba white | metamer white) "
              f"{de76(lab(white, mw), lab(mw, mw)):.3f}")
        print(" patch   ΔE*ab(metamer white)  ΔE*ab(own whites)  combined 95% hw   z")
        rows = []
        for p_m, p_t in zip(sorted(mm["patches"], key=lambda q: q["patch"]), patches):
            a, b = np.asarray(p_m["XYZ"]), np.asarray(p_t["XYZ"])
            de_common = de76(lab(a, mw), lab(b, mw))
            de_own = de76(lab(a, mw), lab(b, white))
            # Combined 95 % half-width of the difference: the two runs are independent, so
            # the half-widths add in quadrature (metamer's against its own white; it reports
            # only per-channel standard errors, not the XYZ correlation needed to redo it).
            hw = math.hypot(p_m["de_ci95"], p_t["de_ci95"])
            rows.append(dict(patch=p_t["patch"], de_common_white=de_common, de_own_whites=de_own,
                             combined_hw95=hw, dY_rel=float(b[1] / a[1] - 1)))
            print(f"  {p_t['patch']:2d}        {de_common:6.3f}              {de_own:6.3f}            "
                  f"{hw:6.3f}        {de_common / (hw / 1.96):5.2f}")
        dc = np.array([r["de_common_white"] for r in rows])
        do = np.array([r["de_own_whites"] for r in rows])
        print(f"ΔE*ab, metamer's white: max {dc.max():.3f} mean {dc.mean():.3f}; "
              f"own whites: max {do.max():.3f} mean {do.mean():.3f}")
        result["comparison"] = dict(
            metamer_seconds=mm.get("seconds"),
            metamer_white=mw.tolist(),
            rows=rows,
            max_de_common_white=float(dc.max()),
            mean_de_common_white=float(dc.mean()),
            max_de_own_whites=float(do.max()),
            mean_de_own_whites=float(do.mean()),
        )
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
