"""Generate the committed SCATMECH reference values for the seed 003 models.

Run once with pySCATMECH installed.  Writes to ``../data``:

* ``scatmech_seed003_diffuse.csv``: ``Diffuse_Subsurface_BRDF_Model``
  (``reflectance.table = rho``), n in [1.0, 2.5], rho in [0, 1]
  -> :class:`scatterbench.models.DiffuseSubsurfaceBRDF`.
* ``scatmech_seed003_single.csv``: ``First_Diffuse_BRDF_Model`` with
  ``Unpolarized_Phase_Function`` around ``Henyey_Greenstein_Phase_Function``,
  no absorption (``phase_function.log_absorption = -1000``: exp(-1000) = 0),
  g in [-0.95, 0.95] -> :class:`scatterbench.models.SingleScatterBRDF` with the depolarizing phase.
* ``scatmech_seed003_btdf.csv``: ``Facet_BRDF_Model`` ``type = 1``
  (transmission), Gaussian and exponential slopes, sigma in [0.05, 1],
  substrate n in [1.1, 2.5] -> :class:`scatterbench.models.FacetBTDF`.
* ``scatmech_seed003_mb.csv``: ``Shadowed_Facet_BRDF_Model`` with
  ``Maxwell_Beard_Shadow_Function`` (tau, Omega), absorbing or transparent
  substrates -> the specular term of :class:`scatterbench.models.MaxwellBeardBRDF`
  (``polarized=True``, ``rho_d = rho_v = 0``).

Geometries are random: polar angles up to 85 deg, every azimuth (the BTDF's
cases are drawn half near the Snell direction, within ~2 sigma, so that most of
them are lit; the other half are drawn uniformly, many of them unreachable).  Usage::

    python references/scripts/make_scatmech_seed003.py [--per-model 200] [--seed 3003]
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
PER_SET = 8


def diffuse_model(n, rho):
    return BRDF_Model(
        "Diffuse_Subsurface_BRDF_Model", substrate=f"({n!r},0)", **{"reflectance.table": repr(rho)}
    )


def single_model(n, g):
    return BRDF_Model(
        "First_Diffuse_BRDF_Model",
        substrate=f"({n!r},0)",
        phase_function="Unpolarized_Phase_Function",
        **{
            "phase_function.phase_function": "Henyey_Greenstein_Phase_Function",
            "phase_function.phase_function.g": repr(g),
            "phase_function.log_absorption": "-1000",
        },
    )


def btdf_model(n, dist, sigma):
    return BRDF_Model(
        "Facet_BRDF_Model",
        type=1,
        substrate=f"({n!r},0)",
        sdf=f"{dist}_Slope_Distribution_Function",
        **{"sdf.s": repr(sigma)},
    )


def mb_model(n, k, dist, sigma, tau, omega):
    return BRDF_Model(
        "Shadowed_Facet_BRDF_Model",
        substrate=f"({n!r},{k!r})",
        sdf=f"{dist}_Slope_Distribution_Function",
        shadow="Maxwell_Beard_Shadow_Function",
        **{"sdf.s": repr(sigma), "shadow.tau": repr(tau), "shadow.Omega": repr(omega)},
    )


def _r(x, k=4):
    return float(np.round(x, k))


def cases(kind, count, rng):
    rows = []
    corners = {
        "diffuse": [(1.0, 1.0), (1.0, 0.0), (2.5, 1.0), (1.5, 0.93), (1.3, 0.5)],
        "single": [(1.0, 0.0), (1.5, 0.95), (1.5, -0.95), (2.5, 0.3), (1.3, 0.0)],
        "btdf": [
            (1.5, "Gaussian", 0.05),
            (1.5, "Gaussian", 1.0),
            (2.5, "Exponential", 0.05),
            (1.1, "Exponential", 1.0),
        ],
        "mb": [(1.5, 0.0, "Gaussian", 0.3, 0.25, 0.7), (1.37, 7.62, "Exponential", 0.1, 0.1, 1.5)],
    }[kind]
    sets = list(corners)
    while len(sets) * PER_SET < count:
        n = _r(rng.uniform(1.0 if kind != "btdf" else 1.1, 2.5))
        if kind == "diffuse":
            sets.append((n, _r(rng.uniform(0.0, 1.0))))
        elif kind == "single":
            sets.append((n, _r(rng.uniform(-0.95, 0.95))))
        elif kind == "mb":
            k = _r(rng.uniform(0.0, 5.0)) if rng.random() < 0.5 else 0.0
            dist = "Gaussian" if rng.random() < 0.5 else "Exponential"
            sig = _r(math.exp(rng.uniform(math.log(0.05), 0.0)), 5)
            sets.append((n, k, dist, sig, _r(rng.uniform(0.05, 1.0)), _r(rng.uniform(0.1, 2.0))))
        else:
            dist = "Gaussian" if rng.random() < 0.5 else "Exponential"
            sets.append((n, dist, _r(math.exp(rng.uniform(math.log(0.05), 0.0)), 5)))
    for params in sets:
        model = {"diffuse": diffuse_model, "single": single_model, "btdf": btdf_model, "mb": mb_model}[kind](
            *params
        )
        for j in range(PER_SET):
            ti = float(rng.uniform(0.0, math.radians(85.0)))
            tr = float(rng.uniform(0.0, math.radians(85.0)))
            if kind == "btdf" and j % 2 == 0:
                # near the refracted direction, where the BTDF is lit
                snell = math.asin(math.sin(ti) / params[0])
                tr = float(np.clip(snell + rng.normal(0.0, 2.0 * params[2]), 0.0, math.radians(85.0)))
                pr = float(rng.normal(0.0, 2.0 * params[2]))
            else:
                pr = float(rng.uniform(-math.pi, math.pi))
            M = np.array(model.MuellerBRDF(ti, tr, pr), dtype=float)
            rows.append([*params, ti, tr, pr, *M.ravel().tolist()])
    return rows[:count]


HEADERS = {
    "diffuse": ["n", "rho"],
    "single": ["n", "g"],
    "btdf": ["n", "sdf", "sigma"],
    "mb": ["n", "k", "sdf", "sigma", "tau", "omega"],
}
WHAT = {
    "diffuse": "Diffuse_Subsurface_BRDF_Model (reflectance.table = rho)",
    "single": "First_Diffuse_BRDF_Model, Unpolarized_Phase_Function(Henyey_Greenstein_Phase_Function g), "
    "log_absorption = -1000",
    "btdf": "Facet_BRDF_Model type = 1 (BTDF; angle columns are theta_i, theta_t, phi_t)",
    "mb": "Shadowed_Facet_BRDF_Model, Maxwell_Beard_Shadow_Function (tau, Omega); substrate n + ik",
}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--per-model", type=int, default=200)
    ap.add_argument("--seed", type=int, default=3003)
    args = ap.parse_args()
    version = metadata.version("pyscatmech")
    stamp = datetime.date.today().isoformat()
    rng = np.random.default_rng(args.seed)
    for kind in ("diffuse", "single", "btdf", "mb"):
        rows = cases(kind, args.per_model if kind != "mb" else 100, rng)
        path = os.path.join(DATA, f"scatmech_seed003_{kind}.csv")
        with open(path, "w", newline="") as fh:
            fh.write(f"# Generated by references/scripts/make_scatmech_seed003.py on {stamp}\n")
            fh.write(f"# pyscatmech {version} (NIST SCATMECH); seed {args.seed}; {WHAT[kind]}\n")
            fh.write("# angles in radians; MuellerBRDF(theta_i, theta_r, phi_r) in psps coordinates, 1/sr.\n")
            w = csv.writer(fh)
            w.writerow(
                HEADERS[kind]
                + ["theta_i", "theta_r", "phi_r"]
                + [f"m{i}{j}" for i in range(4) for j in range(4)]
            )
            for r in rows:
                w.writerow([repr(float(x)) if isinstance(x, (float, np.floating)) else x for x in r])
        print(f"wrote {len(rows)} cases to {path}")


if __name__ == "__main__":
    main()
