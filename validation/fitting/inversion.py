"""Slope-distribution inversion (seed 000 Sec. 4, Fig. 4).

The facet BRDF is linear in the slope density: ``f = P3(zeta) K(geometry)``
(Eq. 49), where ``zeta`` is the slope of the facet that connects the two
directions.  ``K`` is the model evaluated with a *unit* slope density
(:class:`UnitSlopes`, ``P3 = 1`` everywhere), for the row's incident
polarization; the probed slope follows from the internal directions (Eq. 2-7):
``h = k_r' - k_i'``, ``zeta = (h_x / h_z, h_y / h_z)``.  Dividing a measured
BRDF by ``K`` estimates ``P3`` at that slope, one estimate per geometry.

For an isotropic sample the estimates from all geometries should fall on one
curve ``P3(|zeta|)``; its normalization (Eq. 33) is ``2 pi int zeta P3 dzeta``.
The curve is a not-a-knot cubic spline of ``ln P3`` against ``|zeta|`` (exact
for exponential and Gaussian slopes, whose ``ln P3`` is linear or quadratic),
through every distinct probed slope or, for noisy data, through bin means of
``ln P3``; the integral over ``[0, zeta_max]`` is adaptive Gauss-Kronrod on the
spline, and the interpolation error is estimated by the same integral of a
PCHIP interpolant.  The part beyond the largest probed slope is not measured:
it is reported separately (a log-linear extrapolation of the last points), as
the paper's 0.77 leaves it out.  Error bars: bootstrap over rows (seeded).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import integrate, interpolate

from scatterbench.models.base import Sum
from scatterbench.models.facet import _FacetModel, facet_slopes
from scatterbench.models.slopes import UnitSlopes

from .fit import scan_x

__all__ = [
    "UnitSlopes",
    "probed_slopes",
    "unit_response",
    "invert",
    "Curve",
    "fit_curve",
    "bootstrap",
    "collapse",
    "InversionStudy",
    "inversion_study",
    "inversion_figure",
]


def facet_term(model):
    """The single facet model of ``model`` (a FacetBRDF/SubsurfaceFacetBRDF)."""
    if isinstance(model, _FacetModel):
        return model
    if isinstance(model, Sum) and len(model.terms) == 1 and isinstance(model.terms[0][1], _FacetModel):
        return model.terms[0][1]
    raise ValueError(
        f"model: the inversion needs a single facet model (FacetBRDF or SubsurfaceFacetBRDF); got {type(model).__name__}"
    )


def probed_slopes(model, ti, tr, pr):
    """``(zeta_x, zeta_y)`` of the facet that connects the directions (seed 000 Eq. 2-7)."""
    return facet_slopes(ti, tr, pr, facet_term(model)._coating())


def unit_response(model, data):
    """``K``: the BRDF for each row's incident state per unit slope density."""
    m = facet_term(model).replace(slopes=UnitSlopes())
    M = m.mueller(data.theta_i, data.theta_r, data.phi_r)
    S = np.einsum("nij,nj->ni", M, data.incident)
    return S[:, 0] / data.incident[:, 0]


@dataclass
class Inversion:
    zeta_x: np.ndarray
    zeta_y: np.ndarray
    p3: np.ndarray

    @property
    def zeta(self):
        return np.hypot(self.zeta_x, self.zeta_y)


def invert(model, data) -> Inversion:
    """One ``P3`` estimate per data row: measured BRDF / BRDF per unit slope density."""
    K = unit_response(model, data)
    if np.any(K <= 0):
        bad = int(np.flatnonzero(K <= 0)[0])
        where = f"{data.path}:{data.lines[bad]}" if data.lines is not None else f"{data.path}: data row {bad}"
        raise ValueError(f"{where}: the model connects no facet for this geometry (K = 0); mask it")
    zx, zy = probed_slopes(model, data.theta_i, data.theta_r, data.phi_r)
    return Inversion(zx, zy, data.brdf / K)


@dataclass
class Curve:
    zeta: np.ndarray  # knots
    log_p3: np.ndarray
    normalization: float  # 2 pi int_0^zeta_max zeta P3
    interpolation_error: float  # |spline - pchip| of that integral
    zeta_max: float
    tail: float  # extrapolated 2 pi int_zeta_max^inf zeta P3 (not measured)

    def __call__(self, z):
        return np.exp(interpolate.CubicSpline(self.zeta, self.log_p3)(z))


def _knots(zeta, logp, bins):
    if bins is None:
        # distinct slopes (to 1e-12): average repeated probes in log
        order = np.argsort(zeta)
        z, lp = zeta[order], logp[order]
        key = np.round(z, 12)
        uz, start = np.unique(key, return_index=True)
        sums = np.add.reduceat(lp, start)
        counts = np.diff(np.append(start, len(lp)))
        zz = np.add.reduceat(z, start) / counts
        return zz, sums / counts
    edges = np.linspace(0.0, zeta.max() * (1 + 1e-12), bins + 1)
    idx = np.digitize(zeta, edges) - 1
    zz, ll = [], []
    for b in range(bins):
        sel = idx == b
        if sel.any():
            zz.append(zeta[sel].mean())
            ll.append(logp[sel].mean())
    return np.array(zz), np.array(ll)


def fit_curve(inv: Inversion, bins=None) -> Curve:
    """Curve ``P3(|zeta|)`` and its normalization (see module docstring)."""
    if np.any(inv.p3 <= 0):
        raise ValueError("p3: estimates must be > 0 to interpolate ln P3 (mask rows with no signal)")
    z, lp = _knots(inv.zeta, np.log(inv.p3), bins)
    if len(z) < 4:
        raise ValueError(f"bins: need at least 4 distinct slopes for the curve; got {len(z)}")
    spl = interpolate.CubicSpline(z, lp)
    pch = interpolate.PchipInterpolator(z, lp)
    pts = list(z)

    def integral(f):
        with (
            warnings.catch_warnings()
        ):  # roundoff notices near 1e-12 relative: the spline/PCHIP gap measures the error
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            val, _ = integrate.quad(
                lambda t: 2 * math.pi * t * math.exp(f(t)),
                0.0,
                z[-1],
                points=pts[1:-1][:200],
                limit=2000,
                epsabs=0,
                epsrel=1e-12,
            )
        return val

    norm = integral(spl)
    err = abs(norm - integral(pch))
    k = max(3, len(z) // 10)
    slope, icpt = np.polyfit(z[-k:], lp[-k:], 1)
    if slope < 0:
        a = -slope  # P3 ~ exp(icpt - a t): 2 pi int_zm^inf t e^{icpt - a t} dt
        zm = z[-1]
        tail = 2 * math.pi * math.exp(icpt - a * zm) * (zm / a + 1 / a**2)
    else:
        tail = math.inf
    return Curve(z, lp, norm, err, float(z[-1]), tail)


def bootstrap(inv: Inversion, bins=None, n=200, seed=0):
    """Bootstrap over rows: normalization samples and per-knot ``ln P3`` percentiles."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 4]))
    norms = []
    m = len(inv.p3)
    for _ in range(n):
        pick = rng.integers(0, m, m)
        sub = Inversion(inv.zeta_x[pick], inv.zeta_y[pick], inv.p3[pick])
        try:
            norms.append(fit_curve(sub, bins).normalization)
        except ValueError:
            continue
    norms = np.array(norms)
    return {
        "normalization_p16_p50_p84": np.percentile(norms, [16, 50, 84]).tolist(),
        "normalization_p2.5_p97.5": np.percentile(norms, [2.5, 97.5]).tolist(),
        "replicates": int(len(norms)),
    }


def collapse(inv: Inversion, curve: Curve, groups):
    """RMS of ``ln(P3_estimate / curve)`` per group of rows (do the scans fall on one curve?)."""
    r = np.log(inv.p3) - np.log(curve(inv.zeta))
    return {g: float(np.sqrt(np.mean(r[groups == g] ** 2))) for g in dict.fromkeys(groups)}


@dataclass
class InversionStudy:
    """An inversion of measured data: the estimates, the common curve, its bootstrap and
    how closely each scan falls on the curve (see :func:`inversion_study`)."""

    inversion: Inversion
    curve: Curve
    bootstrap: dict
    collapse: dict  # rms ln(P3 / curve) per scan
    groups: np.ndarray  # each row's scan label
    bins: int | None

    def as_dict(self) -> dict:
        """The numbers of ``inversion.json`` (without the input paths)."""
        c, inv = self.curve, self.inversion
        return {
            "rows": len(inv.p3),
            "normalization_measured_range": c.normalization,
            "interpolation_error_estimate": c.interpolation_error,
            "zeta_max": c.zeta_max,
            "tail_beyond_zeta_max_extrapolated": c.tail,
            "bootstrap": self.bootstrap,
            "rms_log_deviation_from_common_curve": self.collapse,
            "paper_value": {"normalization": 0.77, "source": "seed 000 Sec. 4 (measured sample, Fig. 4)"},
            "estimates": {
                "zeta_x": inv.zeta_x.tolist(),
                "zeta_y": inv.zeta_y.tolist(),
                "p3": inv.p3.tolist(),
            },
            "bins": self.bins,
        }


def inversion_study(model, data, bins=None, n_bootstrap=200, seed=0) -> InversionStudy:
    """Seed 000 Sec. 4 on measured data: invert every row, fit the common curve, bootstrap it.

    Parameters
    ----------
    model : FacetBRDF or SubsurfaceFacetBRDF
        A single facet model (its slope distribution is not used).
    data : Dataset
        The rows to invert (already masked).
    bins : int, optional
        Bin ``ln P3`` in ``|zeta|`` (noisy data); default: every distinct slope.
    n_bootstrap : int
        Bootstrap replicates over rows.
    seed : int
        Seeds the bootstrap.

    Returns
    -------
    InversionStudy
    """

    inv = invert(model, data)
    curve = fit_curve(inv, bins=bins)
    boot = bootstrap(inv, bins=bins, n=n_bootstrap, seed=seed)
    _, groups = scan_x(data)
    return InversionStudy(inv, curve, boot, collapse(inv, curve, groups), groups, bins)


def inversion_figure(study: InversionStudy, model):
    """The P3 estimates per scan, the common curve and, for reference, the model's own P3."""
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    inv, curve = study.inversion, study.curve
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for g in dict.fromkeys(study.groups):
        s = study.groups == g
        ax.semilogy(inv.zeta[s], inv.p3[s], ".", ms=4, label=g)
    zz = np.linspace(0, curve.zeta_max, 400)
    ax.semilogy(zz, curve(zz), "k-", lw=1, label="common curve (spline of ln P3)")
    if hasattr(getattr(model, "slopes", None), "p3"):
        ax.semilogy(zz, model.slopes.p3(zz, 0 * zz), "r--", lw=0.8, label="scene's P3 (for reference)")
    ax.set_xlabel("facet slope |zeta|")
    ax.set_ylabel("P3 estimate")
    lo, hi = study.bootstrap["normalization_p2.5_p97.5"]
    ax.set_title(f"normalization {curve.normalization:.4f} (95% bootstrap {lo:.4f}-{hi:.4f})", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig
