"""Generate the committed Mitsuba 3 reference values for the Smith-shadowed facet model.

Run once with Mitsuba installed (``pip install mitsuba``, or ``pip install
".[peers]"``).  Writes ``../data/mitsuba_roughconductor.csv``: Mitsuba's
``roughconductor`` BSDF (``distribution = "ggx"`` and ``"beckmann"``, random
``alpha``, conductor ``eta``/``k`` and geometries) evaluated by ``BSDF.eval``
(``sample_visible`` plays no part in ``eval``) in two scalar variants:

* ``scalar_rgb``: column ``value`` (the first colour channel; the three are
  equal for wavelength-independent ``eta``/``k``);
* ``scalar_spectral_polarized``: columns ``m00..m33``, the Mueller matrix in
  Mitsuba's own Stokes frames, and ``xin_*``/``xout_*``, those frames' first
  axes ``mitsuba.mueller.stokes_basis(k)`` for the incident and the outgoing
  propagation directions ``k``.

Directions: Mitsuba's local frame is ours (normal +z).  ``si.wi`` (towards the
detector) is our reflected direction ``(sin tr cos pr, sin tr sin pr, cos tr)``;
``wo`` (towards the light, in Mitsuba's radiance mode) is the reverse of our
incident ray, ``(-sin ti, 0, cos ti)``.  ``eval`` returns the BRDF times
``cos`` of ``wo``, i.e. ``f cos(theta_i)``.  The test that reads the file
(``tests/test_mitsuba_reference.py``) states the Stokes conventions.  Usage::

    python references/scripts/make_mitsuba_roughconductor.py [--cases 300] [--seed 20261215]
"""

from __future__ import annotations

import argparse
import datetime
import math
from importlib import metadata

import numpy as np
from _write import write_csv

WAVELENGTHS = [450.0, 500.0, 550.0, 600.0]


def random_cases(n, rng):
    """``(distribution, alpha, eta, k, theta_i, theta_r, phi_r)``: alpha 0.02-1 (log-uniform),
    eta 0.2-4, k 0-8 (one in five 0, then eta 1.3-4), polar angles up to 80 deg; three in four scattered
    directions reflected by a facet drawn from the distribution (inside the lobe, where
    the values are not float32 underflow), the others uniform in angle."""
    out = []
    while len(out) < n:
        dist = ("ggx", "beckmann")[len(out) % 2]
        alpha = float(np.exp(rng.uniform(math.log(0.02), 0.0)))
        # k = 0: a dielectric index 1.3-4 (near 1 the reflectance, and Mitsuba's float32 value, vanish)
        k = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 8.0))
        eta = float(rng.uniform(1.3, 4.0)) if k == 0.0 else float(rng.uniform(0.2, 4.0))
        ti, tr = (float(a) for a in rng.uniform(0.0, math.radians(80.0), 2))
        pr = float(rng.uniform(-math.pi, math.pi))
        if rng.random() < 0.75:
            tr, pr = _in_lobe(rng, dist, alpha, ti)
            if tr > math.radians(80.0):
                continue
        out.append((dist, alpha, eta, k, *_float32_angles(ti, tr, pr)))
    return out


def _in_lobe(rng, dist, alpha, ti):
    """Reflected direction ``(theta_r, phi_r)`` off a facet with slopes drawn from the distribution."""
    u = rng.random()
    r = alpha * (math.sqrt(u / (1.0 - u)) if dist == "ggx" else math.sqrt(-math.log1p(-u)))
    phi = rng.uniform(-math.pi, math.pi)
    m = np.array([-r * math.cos(phi), -r * math.sin(phi), 1.0]) / math.sqrt(1.0 + r * r)
    wo = np.array([-math.sin(ti), 0.0, math.cos(ti)])
    wi = 2.0 * (wo @ m) * m - wo
    return math.acos(min(max(wi[2], -1.0), 1.0)), math.atan2(wi[1], wi[0])


def _float32_angles(ti, tr, pr):
    """The angles (float64) of the float32 direction vectors Mitsuba will be given, so that
    the comparison is not blurred by rounding the geometry (narrow lobes are steep)."""
    wi = np.array([math.sin(tr) * math.cos(pr), math.sin(tr) * math.sin(pr), math.cos(tr)], np.float32)
    wo = np.array([-math.sin(ti), 0.0, math.cos(ti)], np.float32)
    wi, wo = wi.astype(float), wo.astype(float)
    ti = math.atan2(-wo[0], wo[2])
    tr = math.atan2(math.hypot(wi[0], wi[1]), wi[2])
    return ti, tr, math.atan2(wi[1], wi[0])


def _directions(mi, ti, tr, pr):
    wi = mi.Vector3f(math.sin(tr) * math.cos(pr), math.sin(tr) * math.sin(pr), math.cos(tr))
    wo = mi.Vector3f(-math.sin(ti), 0.0, math.cos(ti))
    return wi, wo


def evaluate(mi, case, polarized):
    """Mitsuba's ``eval`` for one case: a float, or ``(M (16,), x_in (3,), x_out (3,))``."""
    dist, alpha, eta, k, ti, tr, pr = case
    bsdf = mi.load_dict({"type": "roughconductor", "distribution": dist, "alpha": alpha, "eta": eta, "k": k})
    si = mi.SurfaceInteraction3f()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    wi, wo = _directions(mi, ti, tr, pr)
    si.wi = wi
    if not polarized:
        return float(bsdf.eval(mi.BSDFContext(), si, wo)[0])
    si.wavelengths = WAVELENGTHS
    m = np.array(bsdf.eval(mi.BSDFContext(), si, wo), dtype=float)[:, :, 0]
    x_in = np.array(mi.mueller.stokes_basis(-wo), dtype=float)  # light arrives along -wo
    x_out = np.array(mi.mueller.stokes_basis(wi), dtype=float)  # and leaves along wi
    return m.ravel(), x_in, x_out


def rows_for(variant, cases):
    import mitsuba as mi

    mi.set_variant(variant)
    rows = []
    for case in cases:
        if variant == "scalar_rgb":
            rows.append([variant, *case, evaluate(mi, case, False)] + [""] * 22)
        else:
            m, x_in, x_out = evaluate(mi, case, True)
            rows.append([variant, *case, float(m[0]), *m.tolist(), *x_in.tolist(), *x_out.tolist()])
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=300, help="cases per variant (half GGX, half Beckmann)")
    ap.add_argument("--seed", type=int, default=20261215)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = rows_for("scalar_rgb", random_cases(args.cases, rng))
    rows += rows_for("scalar_spectral_polarized", random_cases(args.cases, rng))
    header = ["variant", "distribution", "alpha", "eta", "k", "theta_i", "theta_r", "phi_r", "value"]
    header += [f"m{i}{j}" for i in range(4) for j in range(4)]
    header += ["xin_x", "xin_y", "xin_z", "xout_x", "xout_y", "xout_z"]
    write_csv(
        "mitsuba_roughconductor.csv",
        [
            f"Generated by references/scripts/make_mitsuba_roughconductor.py on {datetime.date.today()}",
            f"mitsuba {metadata.version('mitsuba')} (drjit {metadata.version('drjit')}); seed {args.seed}; "
            "variants scalar_rgb and scalar_spectral_polarized (float32);",
            "roughconductor BSDF.eval = BRDF * cos(theta_i) (wo = towards the light = -our incident ray,",
            "si.wi = our reflected ray); angles in radians (ours); polarized rows: Mueller matrix in",
            "Mitsuba's Stokes frames, x axes stokes_basis(incident ray) and stokes_basis(reflected ray);",
            f"polarized variant at wavelengths {WAVELENGTHS} nm (flat eta, k), first one stored.",
        ],
        header,
        rows,
    )


if __name__ == "__main__":
    main()
