"""Generate the held-out synthetic measurement of a coated aluminium-flake sample with SCATMECH.

The data are produced by an implementation independent of scatterbench
(NIST's SCATMECH through pySCATMECH: ``Subsurface_Facet_BRDF_Model`` with an
exponential slope distribution) so that ``scatterbench fit`` is tested against
a model it does not share code with.  Run once; the CSV and its JSON sidecar
are committed and the tests read them (CI has no SCATMECH).

Sample (the truth): aluminium flakes ``1.37 + 7.62i`` under a clear coat of
index 1.5, exponential slopes with rms slope 0.1, coverage 1 (seed 000 Sec. 4).

Geometries (200 rows, as seed 000 Sec. 3 measured):

* in-plane, ``theta_i = 60 deg``: 80 signed scattering angles from -85 to 85
  deg (negative = incidence side, ``phi_r = 180``), incident light linearly
  polarized at 45 deg;
* in-plane, ``theta_i = 45 deg``: 60 angles from -85 to 85 deg, 45 deg polarization;
* out-of-plane, ``theta_i = theta_r = 60`` and 45 deg: 30 azimuths each from 3
  to 177 deg, with the incident polarization turning with the azimuth from 45
  deg (p+s) through 90 deg (p) to 135 deg (p-s): ``linear:(45 + phi_r/2)``.

Noise (seeded ``numpy.random.default_rng(SEED)``):

* BRDF: multiplicative log-normal speckle, ``ln b = ln b_true + 0.05 N(0,1)``;
* principal angle ``eta``: ``+ 1.0 deg N(0,1)``;
* ``P`` and ``P_C``: ``+ 0.02 N(0,1)`` each (SCATMECH's facet model does not
  depolarize, so the true ``P`` is 1 and noisy values scatter around it).

The noise levels are written to the sidecar's ``provenance``, NOT to error
columns: the fit must estimate the speckle level itself (``noise.brdf`` free).

Usage::

    python references/scripts/make_scatmech_flake_data.py [--seed 20261122]
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
from importlib import metadata

import numpy as np
from pySCATMECH.brdf import BRDF_Model

from scatterbench.validation.fitting.datafile import write_data  # the installed harness

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DATA = os.path.join(ROOT, "references", "data")
NAME = "scatmech_flake_measurement"

TRUTH = {"substrate.sigma": 0.1, "coating.index": 1.5, "substrate.index[0]": 1.37, "substrate.index[1]": 7.62}
NOISE = {"brdf_frac": 0.05, "eta_deg": 1.0, "P": 0.02, "P_C": 0.02}


def geometries():
    rows = []  # (theta_i, signed theta_r or theta_r, phi_r, incident angle deg)
    for ti, n in ((60.0, 80), (45.0, 60)):
        for s in np.linspace(-85.0, 85.0, n):
            rows.append((ti, abs(s), 180.0 if s < 0 else 0.0, 45.0))
    for ti in (60.0, 45.0):
        for phi in np.linspace(3.0, 177.0, 30):
            rows.append((ti, ti, phi, 45.0 + phi / 2.0))
    return np.array(rows)


def observe(mueller, g, rng, noise):
    """Noisy data columns at geometries ``g`` (rows ``theta_i, theta_r, phi_r, polarizer``,
    degrees) from ``mueller(theta_i, theta_r, phi_r)`` (radians -> 4x4): the BRDF for the
    linearly polarized incident light with log-normal speckle, and eta, P, P_C with
    additive Gaussian noise, the noise levels ``noise`` drawn from ``rng`` in this order."""
    brdf, eta, P, PC = [], [], [], []
    for ti, tr, pr, pol in g:
        M = mueller(math.radians(ti), math.radians(tr), math.radians(pr))
        a = math.radians(pol)
        s_in = np.array([1.0, math.cos(2 * a), math.sin(2 * a), 0.0])
        S = M @ s_in
        brdf.append(S[0])
        eta.append(math.degrees(0.5 * math.atan2(S[2], S[1])))
        P.append(math.sqrt(S[1] ** 2 + S[2] ** 2 + S[3] ** 2) / S[0])
        PC.append(S[3] / S[0])
    brdf, eta, P, PC = map(np.array, (brdf, eta, P, PC))
    if not np.all(brdf > 0):
        raise SystemExit("a geometry has zero BRDF in SCATMECH; choose others")
    n = len(g)
    brdf_obs = brdf * np.exp(noise["brdf_frac"] * rng.standard_normal(n))
    eta_obs = eta + noise["eta_deg"] * rng.standard_normal(n)
    eta_obs = (eta_obs + 90.0) % 180.0 - 90.0  # eta is an axis: keep it in [-90, 90)
    P_obs = P + noise["P"] * rng.standard_normal(n)
    PC_obs = PC + noise["P_C"] * rng.standard_normal(n)
    return {
        "theta_i_deg": g[:, 0],
        "theta_r_deg": g[:, 1],
        "phi_r_deg": g[:, 2],
        "brdf": brdf_obs,
        "eta_deg": eta_obs,
        "P": P_obs,
        "P_C": PC_obs,
        "incident": [f"linear:{float(p)!r}" for p in g[:, 3]],
    }


def provenance(script, version, seed, when):
    """The sidecar's provenance: script, versions, seed, date and the noise model of :func:`observe`."""
    return {
        "script": f"references/scripts/{script}",
        "pyscatmech_version": version,
        "seed": seed,
        "date": when,
        "noise_model": {
            "brdf": f"ln b_obs = ln b_true + {NOISE['brdf_frac']} N(0,1) (log-normal speckle)",
            "eta_deg": f"+ {NOISE['eta_deg']} N(0,1) deg, wrapped to [-90, 90)",
            "P": f"+ {NOISE['P']} N(0,1)",
            "P_C": f"+ {NOISE['P_C']} N(0,1)",
        },
        "noise_levels": NOISE,
    }


def header(script, version, seed, when):
    """The CSV's comment lines."""
    return [
        f"Synthetic measurement from SCATMECH (pySCATMECH {version}), {when}, seed {seed};",
        f"generated by references/scripts/{script}; truth and noise model in the .json sidecar.",
    ]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=20261122)
    args = ap.parse_args(argv)

    model = BRDF_Model(
        "Subsurface_Facet_BRDF_Model",
        substrate=f"({TRUTH['substrate.index[0]']!r},{TRUTH['substrate.index[1]']!r})",
        overcoat=f"({TRUTH['coating.index']!r},0)",
        sdf="Exponential_Slope_Distribution_Function",
        **{"sdf.s": TRUTH["substrate.sigma"]},
    )
    g = geometries()
    rng = np.random.default_rng(args.seed)
    columns = observe(lambda ti, tr, pr: np.array(model.MuellerBRDF(ti, tr, pr), dtype=float), g, rng, NOISE)
    n = len(g)
    version = metadata.version("pySCATMECH")
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d")
    meta = {
        "sample": "synthetic: aluminium flakes (1.37+7.62i) under a clear coat n=1.5, exponential slopes sigma=0.1",
        "instrument": f"SCATMECH Subsurface_Facet_BRDF_Model via pySCATMECH {version} (no instrument)",
        "description": "held-out synthetic measurement for scatterbench fit (independent implementation)",
        "wavelength_nm": 632.8,
        "aperture_deg": 0.0,
        "truth": TRUTH,
        "provenance": provenance("make_scatmech_flake_data.py", version, args.seed, when),
    }
    comments = header("make_scatmech_flake_data.py", version, args.seed, when)
    path = os.path.join(DATA, NAME + ".csv")
    write_data(path, columns, meta, comments)
    print(f"wrote {path} ({n} rows) and its sidecar")


if __name__ == "__main__":
    main()
