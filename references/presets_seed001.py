"""Seed 001's iron plate (Hebert, Emmel & Hersch, "A Prediction Model for
Reflection on Varnished Metallic Plates", section "Measurement Results").

Provenance (numbers typed from the seed text, ``001_74f6c56caffa3995.txt``):
"we took as roughness value m = 0.03, for the varnish index of refraction
n_v = 1.5, for the metal complex index of refraction n = 2.29 + 3.37 i (value
given by [6] for iron with a wavelength of 650 nm).  The ranges of incidence
angle due to non collimated light are [14.2, 19.8], [43.4, 44.7] and [62.8,
63.2] deg."  The paper gives no source distance or sample size; the ranges are
what the point-source geometry must reproduce (:func:`point_source_geometry`
infers ``d / R`` from each range).  Data only: the models are built by the caller.
"""

from __future__ import annotations

import math

__all__ = ["IRON_PLATE", "iron_plate_models", "point_source_geometry"]

#: Parameters of the paper's iron plate (seed 001, "Measurement Results").
IRON_PLATE = {
    "m": 0.03,
    "varnish": 1.5,
    "substrate": 2.29 + 3.37j,
    "wavelength_nm": 650.0,
    "incidence_ranges_deg": ((14.2, 19.8), (43.4, 44.7), (62.8, 63.2)),
    "source": "seed 001 (Hebert, Emmel & Hersch), section 'Measurement Results', Fig. 5; index from Callet [6]",
}


def point_source_geometry(lo_deg, hi_deg):
    """``(psi_c, d / R)``: the central incidence and the source height in units
    of the sample radius for which a disc sample spans incidences ``[lo, hi]``.

    With ``x = d tan(psi)`` (Eq. 26) the disc spans ``x_c - R .. x_c + R``:
    ``d / R = 2 / (tan hi - tan lo)`` and ``tan psi_c = (tan lo + tan hi) / 2``.
    """
    tl, th = math.tan(math.radians(lo_deg)), math.tan(math.radians(hi_deg))
    return math.atan(0.5 * (tl + th)), 2.0 / (th - tl)


def iron_plate_models(normalization="published"):
    """``(cook_torrance, varnished)`` keyword dicts for the iron plate."""
    p = IRON_PLATE
    ct = {"m": p["m"], "substrate": p["substrate"], "normalization": normalization}
    vn = {
        "m_parallel": p["m"],
        "m_perpendicular": p["m"],
        "varnish": p["varnish"],
        "substrate": p["substrate"],
        "normalization": normalization,
    }
    return ct, vn
