"""Closed forms for smooth interfaces, the sigma -> 0 limits of the facet models."""

from __future__ import annotations

import math

import numpy as np

from scatterbench.models.fresnel import fresnel_reflectance, fresnel_transmittance

__all__ = ["flat_coated_reflectance"]


def flat_coated_reflectance(theta_i, coating, substrate):
    """Specular reflectance of a flat substrate under a coating, unpolarized, single pass.

    The ray transmits into the coating (``T(theta_i; 1 -> n)``), reflects once
    from the substrate at the internal angle (``R(theta_i'; n -> n_f)``) and
    transmits out (``T(theta_i'; n -> 1) = T(theta_i; 1 -> n)`` by reciprocity);
    rays reflected back by the coating's underside are not followed, exactly as
    in the facet model (seed 000 Sec. 2.A), so this is the sigma = 0.0 column of
    Table I.  Each polarization is carried separately and averaged at the end.
    """
    theta_i = float(theta_i)
    c = math.cos(theta_i)
    n = float(np.real(coating))
    ts, tp = fresnel_transmittance(np.array(c), 1.0, n)
    ci = math.sqrt(1.0 - (math.sin(theta_i) / n) ** 2)
    if substrate == math.inf:
        rs2 = rp2 = 1.0
    else:
        rs2, rp2 = fresnel_reflectance(np.array(ci), n, complex(substrate))
    return float(0.5 * (ts * ts * rs2 + tp * tp * rp2))
