"""Generate the committed SCATMECH reference values for the facet models.

Run once with pySCATMECH installed (``pip install pyscatmech``; it compiles NIST's
C++ library).  Writes, next to this script's ``../data``:

* ``scatmech_facet.csv``: Mueller BRDFs of ``Facet_BRDF_Model`` (type 0) and
  ``Subsurface_Facet_BRDF_Model`` at random geometries and parameter sets
  (absorbing and transparent substrates, coatings 1.0-2.2, exponential and
  Gaussian slopes, sigma 0.05-1, polar angles up to 80 deg, every azimuth).
* ``table1_scatmech.csv``: Table I of seed 000 integrated from SCATMECH's
  ``Subsurface_Facet_BRDF_Model`` by a quadrature that shares nothing with
  scatterbench's integrator: over facet *slopes* instead of directions, with
  the Jacobian of seed 000 Eq. 46 (``dOmega_r = 4 n^2 cos(tr') cos(alpha) /
  cos(tr) dOmega_n``) and ``dOmega_n = cos^3(theta_n) d^2 zeta`` (Eq. 28).

The tests read these files; CI never builds SCATMECH.  Usage::

    python references/scripts/make_scatmech_facet.py [--cases 600] [--seed 20261122]
"""

from __future__ import annotations

import argparse
import csv
import datetime
import math
import os
from importlib import metadata

import numpy as np
from pySCATMECH.brdf import BRDF_Model

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data")
SQRT6 = math.sqrt(6.0)


def scatmech_model(kind, coating, substrate, dist, sigma):
    sub = f"({substrate.real!r},{substrate.imag!r})"
    sdf = f"{dist}_Slope_Distribution_Function"
    if kind == "facet":
        return BRDF_Model("Facet_BRDF_Model", substrate=sub, type=0, sdf=sdf, **{"sdf.s": sigma})
    return BRDF_Model(
        "Subsurface_Facet_BRDF_Model",
        substrate=sub,
        overcoat=f"({coating!r},0)",
        sdf=sdf,
        **{"sdf.s": sigma},
    )


def _parameter_sets(rng, n_sets):
    """Corners of the requested ranges first, then random parameter sets."""
    sets = []
    for kind in ("facet", "subsurface"):
        for dist in ("Exponential", "Gaussian"):
            for sigma in (0.05, 1.0):
                for substrate in (1.37 + 7.62j, 1.5 + 0j):
                    for coating in (1.0,) if kind == "facet" else (1.0, 2.2):
                        sets.append((kind, coating, substrate, dist, sigma))
    while len(sets) < n_sets:
        kind = "facet" if rng.random() < 0.35 else "subsurface"
        coating = 1.0 if kind == "facet" else float(np.round(rng.uniform(1.0, 2.2), 4))
        if rng.random() < 0.5:  # absorbing: metals and semiconductors
            substrate = complex(np.round(rng.uniform(0.2, 4.5), 4), np.round(rng.uniform(0.01, 8.0), 4))
        else:  # transparent, including substrates below the coating index (TIR at the facet)
            substrate = complex(np.round(rng.uniform(1.2, 3.0), 4), 0.0)
        dist = "Exponential" if rng.random() < 0.5 else "Gaussian"
        sigma = float(np.round(math.exp(rng.uniform(math.log(0.05), math.log(1.0))), 5))
        sets.append((kind, coating, substrate, dist, sigma))
    return sets


def random_cases(n_cases, seed, per_set=10):
    """``per_set`` random geometries (polar angles up to 80 deg, every azimuth) per parameter set."""
    rng = np.random.default_rng(seed)
    rows = []
    for kind, coating, substrate, dist, sigma in _parameter_sets(rng, -(-n_cases // per_set)):
        model = scatmech_model(kind, coating, substrate, dist, sigma)
        for _ in range(per_set):
            ti = float(rng.uniform(0.0, math.radians(80.0)))
            tr = float(rng.uniform(0.0, math.radians(80.0)))
            pr = float(rng.uniform(-math.pi, math.pi))
            M = np.array(model.MuellerBRDF(ti, tr, pr), dtype=float)
            params = [kind, coating, substrate.real, substrate.imag, dist, sigma]
            rows.append([*params, ti, tr, pr, *M.ravel().tolist()])
    return rows[:n_cases]


def _gauss_legendre(n, a, b):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (a + b), 0.5 * (b - a) * w


def _slope_to_direction(zx, zy, ti_int):
    """Internal reflected direction for facet slopes; None where no ray exits upward."""
    nrm = np.array([zx, zy, 1.0]) / math.sqrt(1.0 + zx * zx + zy * zy)
    ki = np.array([math.sin(ti_int), 0.0, -math.cos(ti_int)])
    cos_a = -float(ki @ nrm)
    kr = ki + 2.0 * cos_a * nrm
    return kr, cos_a, nrm[2]


THETA_60 = math.radians(60.0)


def table1_entry(coating, substrate, sigma, n_psi=240, n_rho=120, theta_i=THETA_60):
    """Integrated reflectance of SCATMECH's subsurface facet model, in slope space."""
    n = coating
    model = scatmech_model("subsurface" if n != 1.0 else "facet", n, substrate, "Exponential", sigma)
    ti_int = math.asin(math.sin(theta_i) / n)

    def valid(zx, zy):
        kr, cos_a, _ = _slope_to_direction(zx, zy, ti_int)
        return cos_a > 0 and kr[2] > 0 and n * math.hypot(kr[0], kr[1]) < 1.0

    total = 0.0
    evals = 0
    psis, wpsi = _gauss_legendre(n_psi, 0.0, math.pi)  # mirror symmetry: x2 below
    rho_far = 40.0 * sigma
    scale = sigma / SQRT6
    for psi, wp in zip(psis, wpsi, strict=True):
        c, s = math.cos(psi), math.sin(psi)
        # The valid slopes along this ray from zeta = 0 form an interval [0, rho_b]
        # (checked on a fine sampling); find rho_b by bisection.
        if valid(rho_far * c, rho_far * s):
            rho_b = rho_far
        else:
            lo, hi = 0.0, rho_far
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                if valid(mid * c, mid * s):
                    lo = mid
                else:
                    hi = mid
            rho_b = lo
        samples = np.linspace(0, rho_b, 64)
        assert all(valid(r * c, r * s) for r in samples[:-1]), "valid set is not star-shaped"
        # rho = -scale * ln(1 - u) flattens exp(-rho/scale): rho drho exp(..) -> rho du
        u_b = 1.0 - math.exp(-rho_b / scale)
        us, wu = _gauss_legendre(n_rho, 0.0, u_b)
        for u, w in zip(us, wu, strict=True):
            rho = -scale * math.log1p(-u)
            drho_du = scale / (1.0 - u)
            zx, zy = rho * c, rho * s
            kr, cos_a, nz = _slope_to_direction(zx, zy, ti_int)
            sin_r_int = math.hypot(kr[0], kr[1])
            cos_r_int = kr[2]
            tr = math.asin(min(n * sin_r_int, 1.0))
            pr = math.atan2(kr[1], kr[0])
            f = model.MuellerBRDF(theta_i, tr, pr)[0][0]
            evals += 1
            jac = 4.0 * n * n * cos_r_int * cos_a * nz**3  # f cos(tr) dOmega_r per d^2 zeta
            total += 2.0 * wp * w * f * jac * rho * drho_du
    return total, evals


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=600)
    ap.add_argument("--seed", type=int, default=20261122)
    args = ap.parse_args()
    version = metadata.version("pyscatmech")
    stamp = datetime.date.today().isoformat()
    rows = random_cases(args.cases, args.seed)
    header = ["model", "coating", "substrate_n", "substrate_k", "sdf", "sigma", "theta_i", "theta_r", "phi_r"]
    header += [f"m{i}{j}" for i in range(4) for j in range(4)]
    path = os.path.join(DATA, "scatmech_facet.csv")
    with open(path, "w", newline="") as fh:
        fh.write(f"# Generated by references/scripts/make_scatmech_facet.py on {stamp}\n")
        fh.write(f"# pyscatmech {version} (NIST SCATMECH); seed {args.seed}; angles in radians;\n")
        fh.write("# MuellerBRDF(theta_i, theta_r, phi_r) in psps coordinates, 1/sr.\n")
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([repr(float(x)) if isinstance(x, (float, np.floating)) else x for x in r])
    print(f"wrote {len(rows)} cases to {path}")

    table = []
    for sub_name, sub in (
        ("perfect conductor", None),
        ("aluminium", 1.37 + 7.62j),
        ("silicon", 3.88 + 0.02j),
    ):
        for n in (1.0, 1.5, 2.0):
            for sigma in (0.1, 0.2):
                # SCATMECH takes no infinite index: a perfect conductor is approached by
                # n_f = 1e6 (1 + i), where |r| differs from 1 by ~1e-6.
                s = complex(1e6, 1e6) if sub is None else sub
                val, ev = table1_entry(n, s, sigma)
                coarse, _ = table1_entry(n, s, sigma, n_psi=120, n_rho=60)
                table.append([sub_name, n, sigma, val, abs(val - coarse), ev])
                print(sub_name, n, sigma, f"{val:.6f}", f"(120x60 grid: {coarse:.6f})")
    path = os.path.join(DATA, "table1_scatmech.csv")
    with open(path, "w", newline="") as fh:
        fh.write(
            f"# Generated by references/scripts/make_scatmech_facet.py on {stamp}; pyscatmech {version}\n"
        )
        fh.write(
            "# Table I (theta_i = 60 deg, exponential slopes) from SCATMECH's Subsurface_Facet_BRDF_Model\n"
        )
        fh.write("# (Facet_BRDF_Model for coating 1.0) integrated over facet slopes on a 240 x 120\n")
        fh.write(
            "# Gauss-Legendre grid (Eq. 46 Jacobian); 'grid_change' is the difference from a 120 x 60 grid.\n"
        )
        fh.write("# Perfect conductor approximated by n_f = 1e6(1+i).\n")
        w = csv.writer(fh)
        w.writerow(["substrate", "coating", "sigma", "reflectance", "grid_change", "evaluations"])
        for r in table:
            w.writerow([r[0], r[1], r[2], repr(float(r[3])), repr(float(r[4])), r[5]])
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
