"""How closely a compiled float64 kernel agrees with the numpy reference: a tolerance derived
from the model's conditioning, as :mod:`scatterbench.models.float32_domain` derives float32's.

Both paths evaluate the same formulas in float64 but not with the same operations: the kernels
take sines, cosines and exponentials from polynomials (:mod:`scatterbench.models.kernels.vector_math`,
within an ulp or two), sum in another order and fuse what numpy keeps apart.  A formula whose
result is insensitive to its inputs' last bits gives the same number to a few hundred roundings;
one that amplifies them (a narrow lobe) cannot, on either path, and the difference between the
paths is then as large as their own errors.

**Measure.**  Per geometry, ``max |M_kernel - M_numpy| / |M00_numpy|`` over the 16 elements
(``tests/test_kernels.py``): relative to the geometry's own ``M00``, so a lobe's tail is held as
tightly as its peak.

**Bound.**  ``EPS * kappa`` (``EPS`` the float64 machine epsilon, 2.2e-16), ``kappa`` the sum of:

* arithmetic, every kernel: :data:`ARITHMETIC` = 256, as float32's (a few hundred roundings
  without cancellation).  Measured on the lobe-free kernels: <= 51 EPS (diffuse subsurface,
  single scattering at |g| <= 0.9, the BTDF of ``tests/test_kernels.py``).
* lobe width ``w`` (facet, subsurface, Maxwell-Beard, BTDF, Cook-Torrance):
  ``SLOPE_ERROR * LOG_SLOPE[kind] / w``.  The slope ``z = h_xy / h_z`` of the bisector comes
  from two directions: ``h_x`` sums two products of a sine and a cosine, each within an EPS
  or two on each path, so ``z`` differs between the paths by up to :data:`SLOPE_ERROR` = 4 EPS
  (absolute; near specular, where the lobe is, ``h_z >= 1``).  A lobe ``P(z / w)`` then moves by
  ``|d ln P / du| dz / w`` of its own value, ``u = z / w``: ``2 u`` for the Gaussian family
  (Gaussian, Beckmann, strokes, Cook-Torrance's ``m``) up to ``u = sqrt(708.4)``, where
  ``exp(-u^2)`` leaves the normal range (53.2); ``sqrt 6`` for the exponential; at most 2 for
  GGX (``4 u / (1 + u^2)``).  A relative error of the slope (far from specular, ``h_z`` small)
  is amplified in the tail by ``u |d ln P / du|`` (:data:`LOG_TAIL`): ``2 u^2`` up to 2 x 708.4
  for the Gaussian family, ``sqrt 6 u`` up to 708.4 for the exponential, 4 for GGX; charged
  the same 4 EPS.  The difference grows as ``1 / w`` down to the narrowest declared width
  (Gaussian ``sigma = 1e-8``: 2.3e-7, the ~1e-6 that
  :data:`scatterbench.models.constraints.SLOPE_WIDTH_MIN` was chosen to keep).  A BTDF's slope
  comes from ``k_in - n k_out`` (``|h| >= n - 1``): times ``(n + 1) / (n - 1)``.
* Henyey-Greenstein ``g`` (single scattering): ``12 / (1 - |g|)^2``, float32's derivation (the
  phase's base ``u^2 + 2 |g| v`` carries ``<= 8 EPS`` and enters as ``base^(-3/2)``): near
  backscatter at ``g = -0.9999`` the paths differ by 6.7e-8, a quarter of the bound.
* Maxwell-Beard's ``tau`` and ``Omega``: ``2 SLOPE_ERROR (1 / tau + 1 / Omega)``, float32's with
  the float64 angles' error (``exp(-2 beta / tau)`` and ``theta_N / Omega``).

Measured against the bound (``python benchmarks/kernel_tolerance.py``: 21 models, random,
extreme and near-specular geometries): 0.00-0.36 of it, none above.

**Which models need more than the flat 1e-12 (4504 EPS) of earlier tests:** every lobe of the
Gaussian family (its tail term alone is 5667 EPS; measured: 1024-1532 EPS at width 0.3, 6650 at
0.01), exponential lobes narrower than ~7e-3 and GGX narrower than ~2e-3 (their width terms),
single scattering at ``|g| > 0.95``, Maxwell-Beard at ``tau`` or ``Omega`` below ~2e-3, and
BTDFs of an index near 1.  Lobe-free kernels (diffuse subsurface, single scattering at moderate
``g``) and wide exponential or GGX lobes are held tighter than before: ``256 EPS`` = 5.7e-14
plus their terms.
"""

from __future__ import annotations

import math

import numpy as np

from .kernel_specs import (
    ANISO_EXPONENTIAL,
    ANISO_GAUSSIAN,
    ANISO_GGX,
    EXPONENTIAL,
    GAUSSIAN,
    GGX,
    STROKE,
    named_rows,
)

__all__ = [
    "EPS",
    "ARITHMETIC",
    "SLOPE_ERROR",
    "LOG_SLOPE",
    "LOG_TAIL",
    "kernel_condition",
    "kernel_tolerance",
]

EPS = float(np.finfo(np.float64).eps)
#: a kernel's rounding (in units of EPS), as float32_domain's
ARITHMETIC = 256.0
#: the slope's absolute difference between the two paths (EPS)
SLOPE_ERROR = 4.0
#: ``max |d ln P / du|`` over the normal range of each slope kind's density (unit width)
_X = -math.log(np.finfo(np.float64).tiny)  # 708.4: exp(-x) is normal for x <= _X
_GAUSS = 2.0 * math.sqrt(_X)
LOG_SLOPE = {
    GAUSSIAN: _GAUSS,
    ANISO_GAUSSIAN: _GAUSS,
    STROKE: _GAUSS,
    EXPONENTIAL: math.sqrt(6.0),
    ANISO_EXPONENTIAL: math.sqrt(6.0),
    GGX: 2.0,
    ANISO_GGX: 2.0,
}
#: ``max u |d ln P / du|`` over the normal range: a relative error of the slope, amplified in
#: the tail (``2 u^2`` for the Gaussian family, ``sqrt 6 u`` for the exponential, both up to
#: where ``P`` leaves the normal range; ``4 u^2 / (1 + u^2) <= 4`` for GGX)
LOG_TAIL = {
    k: 2.0 * _X if v == _GAUSS else (_X if v == math.sqrt(6.0) else 4.0) for k, v in LOG_SLOPE.items()
}


def _width(kind, w):
    """The lobe's term: the slope's absolute error over the width, and its relative error over
    the lobe's tail (``u |d ln P / du|`` at the largest ``u`` of the normal range)."""
    with np.errstate(divide="ignore"):
        return SLOPE_ERROR * (LOG_SLOPE.get(kind, 0.0) / np.asarray(w, dtype=float) + LOG_TAIL.get(kind, 0.0))


def _facet(rows, iopt):
    return {"lobe width": _width(int(iopt[0]), np.minimum(rows["sx"], rows["sy"]))}  # UnitSlopes: 0


def _maxwell(rows, iopt):
    out = _facet(rows, iopt)
    out["Maxwell-Beard tau, Omega"] = 2.0 * SLOPE_ERROR * (1.0 / rows["tau"] + 1.0 / rows["omega"])
    return out


def _cook(rows, iopt):
    return {"lobe width": _width(GAUSSIAN, np.minimum(rows["m_parallel"], rows["m_perpendicular"]))}


def _btdf(rows, iopt):
    n = rows["substrate"]
    with np.errstate(divide="ignore"):
        ratio = np.where(n == 1.0, 1.0, (n + 1.0) / (n - 1.0))
    return {"lobe width": ratio * _facet(rows, iopt)["lobe width"]}


def _single(rows, iopt):
    gap = 1.0 - np.abs(rows["g"])
    return {"phase g near +-1": 12.0 / (gap * gap)}


_TERMS = {
    "facet": _facet,
    "maxwell": _maxwell,
    "cook": _cook,
    "btdf": _btdf,
    "single": _single,
    "diffuse": lambda rows, iopt: {},
}


def kernel_condition(code, rows, iopt):
    """``(kappa, terms)`` per element of the kernel's parameter ``rows`` (by name, flat arrays of
    one length): the float64 kernel agrees with the numpy reference to ``EPS * kappa`` of each
    geometry's ``M00`` (module docstring)."""
    n = len(next(iter(rows.values())))
    terms = {"arithmetic": np.full(n, ARITHMETIC)}
    terms.update(
        {k: np.broadcast_to(np.asarray(v, dtype=float), (n,)) for k, v in _TERMS[code](rows, iopt).items()}
    )
    return sum(terms.values()), terms


def kernel_tolerance(model) -> float:
    """``EPS * kappa`` of a model a kernel covers (``model._kernel_spec()`` not ``None``; a model
    set: its worst element)."""
    kappa, _ = kernel_condition(*named_rows(model))
    return float(EPS * np.max(kappa))
