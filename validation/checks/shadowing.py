"""Energy with Smith shadowing-masking (issue 15): perfect-conductor albedo versus incidence.

Without shadowing the facet model's integrated reflectance is bounded by the hit fraction
``H = C (1 + Lambda)`` (:mod:`scatterbench.validation.numerics.energy`), which exceeds 1 near grazing
incidence on rough surfaces.  The separable Smith ``G = G1(i) G1(o)`` divides the
incident side by exactly ``1 + Lambda``, so with it a perfect conductor's albedo stays
at or below 1 (the outgoing ``G1 <= 1`` can only remove light).  :func:`conductor_albedo_curves`
computes both for Gaussian (Beckmann) ``sigma`` and GGX ``alpha`` in {0.1, 0.3, 1} (the
report's conservation figure draws them), :func:`check_smith_albedo` holds the Smith
curves to ``<= 1 + the integrator's error estimate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scatterbench import models
from scatterbench.validation.numerics.integrate import integrated_reflectance

from .registry import check, judge

__all__ = ["AlbedoCurve", "conductor_albedo_curves", "check_smith_albedo", "WIDTHS", "ANGLES_DEG"]

#: (slope family, width): Gaussian rms slope sigma (Beckmann alpha), GGX alpha
WIDTHS = (("gaussian", 0.1), ("gaussian", 0.3), ("gaussian", 1.0), ("ggx", 0.1), ("ggx", 0.3), ("ggx", 1.0))
#: incidences (deg) of the full run; quick runs use :data:`QUICK_ANGLES_DEG`
ANGLES_DEG = (0.0, 30.0, 60.0, 75.0, 85.0, 88.0, 89.5, 89.9, 89.99)
QUICK_ANGLES_DEG = (0.0, 85.0, 89.99)
#: the integrator's tolerance for the curves
TOL = 1e-4


@dataclass(frozen=True)
class AlbedoCurve:
    """Perfect-conductor albedo of :class:`scatterbench.models.FacetBRDF` versus incidence, one slope
    distribution and shadowing choice; ``error`` the integrator's estimates."""

    family: str
    width: float
    shadowing: str
    theta_i_deg: tuple
    albedo: tuple
    error: tuple
    converged: tuple

    @property
    def label(self) -> str:
        name = "sigma" if self.family == "gaussian" else "alpha"
        return f"{self.family} {name} = {self.width:g}, shadowing {self.shadowing}"


def _slopes(family, width):
    if family == "gaussian":
        return models.GaussianSlopes(sigma=width)
    if family == "ggx":
        return models.GGXSlopes(alpha=width)
    raise ValueError(f"family must be 'gaussian' or 'ggx'; got {family!r}")


def conductor_albedo_curves(widths=WIDTHS, angles_deg=ANGLES_DEG, shadowings=("none", "smith"), tol=TOL):
    """Perfect-conductor (``substrate = math.inf``) albedo of the exposed facet model
    versus incidence, with and without Smith shadowing.

    Parameters
    ----------
    widths : sequence of (str, float)
        ``("gaussian", sigma)`` or ``("ggx", alpha)``.
    angles_deg : sequence of float
        Incidence angles in degrees, in [0, 90).
    shadowings : sequence of str
        The ``shadowing`` choices of :class:`scatterbench.models.FacetBRDF` to compute.
    tol : float
        Tolerance of :func:`scatterbench.validation.integrated_reflectance`.

    Returns
    -------
    list of AlbedoCurve
    """
    out = []
    for family, width in widths:
        for shadowing in shadowings:
            model = models.FacetBRDF(slopes=_slopes(family, width), substrate=math.inf, shadowing=shadowing)
            rs = [integrated_reflectance(model, math.radians(a), tol=tol) for a in angles_deg]
            out.append(
                AlbedoCurve(
                    family,
                    float(width),
                    shadowing,
                    tuple(float(a) for a in angles_deg),
                    tuple(r.value for r in rs),
                    tuple(r.error for r in rs),
                    tuple(bool(r.converged) for r in rs),
                )
            )
    return out


def _worst_first(x):
    """Sort key of an excess: NaN (an integral that did not converge) above everything, so a
    maximum keeps it wherever it stands (``max`` alone keeps a NaN only when it comes first)."""
    return math.inf if math.isnan(x) else x


def _excess(curve):
    """Largest ``albedo - 1 - error`` of a curve (NaN where an integral did not converge)."""
    vals = [
        v - 1.0 - e if ok else math.nan
        for v, e, ok in zip(curve.albedo, curve.error, curve.converged, strict=True)
    ]
    return max(vals, key=_worst_first)


@check(paper="issue 15: Smith shadowing-masking keeps a perfect conductor's albedo <= 1")
def check_smith_albedo(ctx, curves=None):
    """``curves``: :func:`conductor_albedo_curves` (the run computes them once, quick runs at
    fewer incidences); every Smith curve must stay at or below ``1 + error``."""
    if curves is None:
        angles = QUICK_ANGLES_DEG if ctx.quick else ANGLES_DEG
        curves = ctx.compute(conductor_albedo_curves, angles_deg=angles)
    smith = [c for c in curves if c.shadowing == "smith"]
    none = [c for c in curves if c.shadowing == "none"]
    worst = max(smith, key=lambda c: _worst_first(_excess(c)))
    top = max(none, key=lambda c: max(c.albedo), default=None)
    unshadowed = "" if top is None else f"; without shadowing up to {max(top.albedo):.4g} ({top.label})"
    return judge(
        "energy: perfect-conductor albedo with Smith shadowing - 1 - integration error",
        _excess(worst),
        0.0,
        f"max over {len(smith)} curves at {len(worst.theta_i_deg)} incidences up to "
        f"{max(worst.theta_i_deg):g} deg, worst {worst.label}, largest albedo {max(worst.albedo):.6f}"
        + unshadowed,
    )
