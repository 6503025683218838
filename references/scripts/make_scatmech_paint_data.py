"""Generate two held-out synthetic measurements with SCATMECH for seed 003's model comparison.

Seed 003 (Sec. 4) sets its three-term combination for paints (facet reflection
by the surface + single volume scattering + totally diffuse volume scattering,
under a smooth interface) against the empirical Maxwell-Beard BRDF.  To test
``scatterbench study compare`` on that pairing, each hypothesis gets a data set
made by an implementation independent of scatterbench (NIST's SCATMECH through
pySCATMECH) at the geometries, incident polarizations and noise model of the
coated-flake measurement (``make_scatmech_flake_data.py``: 200 rows at theta_i
= 60 and 45 deg, in-plane and out-of-plane; 5% log-normal speckle, eta +- 1
deg, P and P_C +- 0.02):

* ``scatmech_paint_measurement``: a red-paint-like combination, the sum of
  ``Facet_BRDF_Model`` (exposed facets of the binder, n = 1.5, Gaussian slopes
  rms 0.05), ``First_Diffuse_BRDF_Model`` (single scattering under the smooth
  interface, ``Unpolarized_Phase_Function`` around the Henyey-Greenstein
  function with g = 0.3, no absorption) and ``Diffuse_Subsurface_BRDF_Model``
  (rho = 0.1).  Its scene is ``references/scenes/red_paint_fit.toml``.
* ``scatmech_mb_measurement``: a Maxwell-Beard surface, SCATMECH's
  ``Shadowed_Facet_BRDF_Model`` with ``Maxwell_Beard_Shadow_Function`` (n =
  1.5, Gaussian slopes rms 0.1, tau = 0.25 rad, Omega = 0.7 rad) plus the
  model's Lambertian ``rho_d = 0.02`` and volumetric ``2 rho_v / (cos ti + cos
  tr)`` with ``rho_v = 0.01`` /sr, both depolarizing (SCATMECH has no class for
  these two one-line terms; they are added here).  Its scene is
  ``references/scenes/maxwell_beard_fit.toml``.

Usage (pySCATMECH installed)::

    python references/scripts/make_scatmech_paint_data.py [--seed 20261123]
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
from importlib import metadata

import numpy as np
from make_scatmech_flake_data import DATA, NOISE, geometries, header, observe, provenance
from pySCATMECH.brdf import BRDF_Model

from scatterbench.validation.fitting.datafile import write_data  # the installed harness

PAINT_TRUTH = {"coating.roughness.sigma": 0.05, "volume.g": 0.3, "volume.rho": 0.1, "coating.index": 1.5}
MB_TRUTH = {
    "substrate.sigma": 0.1,
    "substrate.rho_d": 0.02,
    "substrate.rho_v": 0.01,
    "substrate.tau_deg": math.degrees(0.25),
    "substrate.omega_deg": math.degrees(0.7),
    "substrate.index": 1.5,
}


def paint_mueller():
    n = PAINT_TRUTH["coating.index"]
    surface = BRDF_Model(
        "Facet_BRDF_Model",
        substrate=f"({n!r},0)",
        type=0,
        sdf="Gaussian_Slope_Distribution_Function",
        **{"sdf.s": PAINT_TRUTH["coating.roughness.sigma"]},
    )
    single = BRDF_Model(
        "First_Diffuse_BRDF_Model",
        substrate=f"({n!r},0)",
        phase_function="Unpolarized_Phase_Function",
        **{
            "phase_function.phase_function": "Henyey_Greenstein_Phase_Function",
            "phase_function.phase_function.g": repr(PAINT_TRUTH["volume.g"]),
            "phase_function.log_absorption": "-1000",
        },
    )
    diffuse = BRDF_Model(
        "Diffuse_Subsurface_BRDF_Model",
        substrate=f"({n!r},0)",
        **{"reflectance.table": repr(PAINT_TRUTH["volume.rho"])},
    )
    models = (surface, single, diffuse)
    return lambda ti, tr, pr: sum(np.array(m.MuellerBRDF(ti, tr, pr), dtype=float) for m in models)


def mb_mueller():
    facet = BRDF_Model(
        "Shadowed_Facet_BRDF_Model",
        substrate=f"({MB_TRUTH['substrate.index']!r},0)",
        sdf="Gaussian_Slope_Distribution_Function",
        shadow="Maxwell_Beard_Shadow_Function",
        **{
            "sdf.s": repr(MB_TRUTH["substrate.sigma"]),
            "shadow.tau": repr(math.radians(MB_TRUTH["substrate.tau_deg"])),
            "shadow.Omega": repr(math.radians(MB_TRUTH["substrate.omega_deg"])),
        },
    )

    def mueller(ti, tr, pr):
        M = np.array(facet.MuellerBRDF(ti, tr, pr), dtype=float)
        M[0, 0] += MB_TRUTH["substrate.rho_d"] + 2.0 * MB_TRUTH["substrate.rho_v"] / (
            math.cos(ti) + math.cos(tr)
        )
        return M

    return mueller


SETS = {
    "scatmech_paint_measurement": (
        paint_mueller,
        PAINT_TRUTH,
        "synthetic: glossy paint, n=1.5 binder with a Gaussian-rough surface (rms slope 0.05), single scattering "
        "by a Henyey-Greenstein pigment (g=0.3, depolarizing phase) and totally diffuse scattering (rho=0.1)",
        "SCATMECH Facet_BRDF_Model + First_Diffuse_BRDF_Model + Diffuse_Subsurface_BRDF_Model",
    ),
    "scatmech_mb_measurement": (
        mb_mueller,
        MB_TRUTH,
        "synthetic: Maxwell-Beard surface, n=1.5, Gaussian slopes rms 0.1, tau 0.25 rad, Omega 0.7 rad, "
        "rho_d 0.02/sr, rho_v 0.01/sr",
        "SCATMECH Shadowed_Facet_BRDF_Model (Maxwell_Beard_Shadow_Function) + Lambertian + volumetric terms",
    ),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=20261123)
    args = ap.parse_args(argv)

    version = metadata.version("pySCATMECH")
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d")
    g = geometries()
    for k, (name, (make, truth, sample, instrument)) in enumerate(SETS.items()):
        seed = args.seed + k
        columns = observe(make(), g, np.random.default_rng(seed), NOISE)
        meta = {
            "sample": sample,
            "instrument": f"{instrument} via pySCATMECH {version} (no instrument)",
            "description": "held-out synthetic measurement for scatterbench study compare (seed 003 Sec. 4 pairing)",
            "wavelength_nm": 632.8,
            "aperture_deg": 0.0,
            "truth": truth,
            "provenance": provenance("make_scatmech_paint_data.py", version, seed, when),
        }
        comments = header("make_scatmech_paint_data.py", version, seed, when)
        path = os.path.join(DATA, name + ".csv")
        write_data(path, columns, meta, comments)
        print(f"wrote {path} ({len(g)} rows) and its sidecar")


if __name__ == "__main__":
    main()
