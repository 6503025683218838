"""The float32-safe parameter domain of the compiled kernels, and the float64 fallback outside it.

``precision="float32"`` runs the float32 kernels (:mod:`scatterbench.models.kernels`): the float64 formulas in
float32 arithmetic, whose machine epsilon is ``EPS = 2^-23`` (1.19e-7), smallest normal number
``TINY`` (1.18e-38) and largest ``HUGE`` (3.40e38).  Where a model's parameters let that
arithmetic lose more than :data:`TOLERANCE` of the model's scale, :class:`scatterbench.models.Model` evaluates
the request in float64 and rounds the result to float32 instead (``model.float32_fallback`` says
why).  The choice is made once per model from its parameters (a model set: from all its
elements, and one fallback element sends the whole set to float64), never per geometry.

**Error measure.**  ``E = max |M32 - M64| / max M64_00`` over every element and geometry (the
trade-off study's precision knob, :func:`scatterbench.validation.studies.tradeoff.precision_error`): relative
to the model's peak, because a lobe's tails leave float32's range (``exp(-104)`` underflows)
long before float64's, which no parameter can help.  Polar angles up to 89 degrees: every
BRDF carries ``1 / cos(theta)`` factors whose condition ``theta tan(theta)`` grows without bound
at grazing, in either precision.

**Bound.**  ``E <= EPS * kappa`` with the condition number ``kappa`` of :func:`condition`, a sum
of first-order terms (each input or intermediate's float32 error times the result's relative
sensitivity to it; ``u = EPS / 2`` is the unit roundoff, ``Delta`` the sine error below):

* arithmetic, every kernel: :data:`ARITHMETIC` = 256.  A kernel rounds a few hundred times
  (each ``<= u``; without cancellation they add up to ``<= 150 EPS``), and rounding the polar
  angles to float32 moves ``1 / cos(theta)`` by ``theta tan(theta) u <= 45 EPS`` each at 89 deg.
* sines, the kernels that take ``sin = sqrt(1 - cos^2)`` (facet, Maxwell-Beard, Cook-Torrance,
  single scattering): ``4 Delta / EPS`` = 8192.  ``cos(theta)`` rounds to 1 below ``theta =
  sqrt(EPS / 2)``, where the sine comes out 0; above, ``cos = 1 - k EPS / 2`` gives the sine
  ``sqrt(k EPS)`` for every ``theta`` in ``sqrt((k -+ 1/2) EPS)``, within 1e-4; and away from
  normal incidence its error is ``~ EPS / sin``.  So the sine's absolute error is ``<= Delta
  = sqrt(EPS / 2)`` = 2.4e-4 (:data:`SINE`), 2048 EPS, where a directly computed sine has a
  few EPS.  The s/p bases and the Jones elements are sums of terms linear in a sine, with
  coefficients up to the element's scale, and ``|J|^2`` doubles the error: ``4 Delta``.
  The kernels now evaluate that formula in float64 and round it
  (:func:`scatterbench.models.kernels.common.polar`), which keeps their sines within 1.125 EPS; the domain
  still charges ``Delta``, an allowance that also covers what a bound from the accurate sines
  would have to add and that is not derived here: the polar angles' own rounding (up to
  ``(pi / 4) EPS`` per sine and cosine) moved into the slopes by ``1 / h_z``, which grows
  towards grazing.  (``tests/test_float32_domain.py`` measures a varnished Cook-Torrance
  lobe of ``m = 1e-3`` erring by more than a bound that charges the sines 1.125 EPS.)
* lobe width ``w`` (the narrowest of ``sigma``, ``alpha``, the stroke ``m``; Cook-Torrance's
  ``m``): ``L Delta / (EPS w)``.  The bisector's slope ``z = h_x / h_z`` has ``h_z >= 1`` near
  normal, so the sines' error moves it by ``<= Delta``; a slope density ``P(z / w)`` then moves
  by ``L Delta / w`` of its peak, ``L = max |P'(u)| / P(0)``: ``sqrt 6`` (exponential, at its
  cusp), ``sqrt(2 / e)`` (Gaussian, Beckmann, strokes), ``(4 / sqrt 5)(5 / 6)^3`` (GGX).
* relative index ``m`` (substrate over coating), facet and Cook-Torrance kernels; 0 for
  ``m = 1`` exactly (both precisions take the kernels' ``m == 1`` branch) and for a perfect
  conductor:

  - rounding ``m`` (``<= 1.5 EPS |m|``) moves Fresnel coefficients ``~ (m - 1)`` by
    ``1.5 EPS |m| / |m - 1|`` relative, and ``|r|^2`` doubles it: ``4 |m| / |m - 1|``;
  - near the critical angle: ``w^2 = m^2 - sin^2`` (``sin^2`` in [0, 1]) carries ``~ 2 EPS``
    of rounding, so ``w`` one of ``EPS / |w|``, and ``|w| >= sqrt(d)`` with ``d`` the distance
    from ``m^2`` to [0, 1]: ``w`` moves by ``<= W EPS``, ``W = min(sqrt(2 / EPS), 1 /
    sqrt(d))`` (``sqrt(2 / EPS)`` = 4096 at the critical angle of a real ``m < 1``).
    ``r = (c - w) / (c + w)``, ``|r| <= 1`` there, moves by ``2 W EPS / |c + w|`` with ``|c +
    w| >= max(c_c, sqrt d)``, ``c_c = sqrt(max(0, 1 - Re m^2))`` the cosine at the critical
    angle: ``4 W / max(c_c, sqrt d)``.  ``K ~ 1 / (m^2 c + w)`` and ``r_p`` divide by ``m^2
    c ~ |m|^2`` where ``w`` vanishes: ``W / |m|^2`` (the small-index hazard: at ``|m| ~ 1e-16``
    float32 loses ``m^2`` beside 1 altogether).
* coating ``n`` near 1 (but not 1): the internal cosine ``sqrt(n^2 - 1 + cos^2) / n`` rounds
  ``n^2 - 1`` (``~ EPS n^2``) beside ``cos^2 >= cos^2(89 deg)``: ``2 n^2 / (n^2 - 1 +
  cos^2(89 deg))``, at most 6600.
* Henyey-Greenstein ``g``: ``12 / (1 - |g|)^2 + 0.75 sqrt|g| (Delta / EPS) / (1 - |g|)``.  The
  phase's ``base = 1 + g^2 - 2 g cos`` is ``>= (1 - |g|)^2`` and carries ``<= 8 EPS`` of
  rounding; it enters as ``base^(-3/2)``.  Near normal incidence the sines' ``Delta`` moves
  ``cos`` by ``s Delta`` where ``base >= (1 - |g|)^2 + |g| s^2``, at most ``sqrt|g| Delta /
  (2 (1 - |g|))`` relative.
* Maxwell-Beard's ``tau`` and ``Omega``: ``2 (Delta / EPS) (1 / tau + 1 / Omega)``.
  ``beta = acos(c)`` with ``c`` near 1 has the sine's error ``<= Delta``, and ``theta_N =
  atan(sqrt(t) / (cos + cos))`` with ``t`` near 0 (rounded to ``~ 2 EPS``) one of ``<= 2
  Delta``; ``exp(-2 beta / tau)`` and ``theta_N / Omega`` scale them by ``2 / tau`` and
  ``1 / Omega``, and the shadowing function's relative sensitivity to either is ``<= 1``.
* facet transmission (:class:`scatterbench.models.FacetBTDF`, index ``n``, sines from ``math.sin``):
  ``(n + 1) / (n - 1) (4 + 2 L / w + 16 w)``.  ``h = k_in - n k_out`` has ``|h| >= n - 1`` and
  an error ``<= 2 EPS (n + 1)``: the factors ``(n - 1)`` of the coefficients and ``1 / |h|^2``
  (the 4), the slope ``h_xy / h_z`` within a narrow lobe (``2 L / w``), and for a wide lobe the
  peak at nearly vertical facets, ``m_z ~ 1 / (sqrt 2 w)``, where ``1 / m_z^4`` multiplies
  ``h_z``'s relative error by 4 (the ``16 w``).

**Domain.**  ``EPS * kappa <= TOLERANCE`` (1e-2: float32 keeps two digits of the peak), and

* every kernel parameter rounds to a finite float32 (a perfect conductor's ``inf`` is exact),
  zero or normal (``>= TINY``: a subnormal has lost digits), and ``<= sqrt(HUGE)`` (the kernels
  square them); rotations (:data:`ANGLE_ROWS`) are reduced to (-pi, pi] in float64 first;
* the model's scale, ``M00`` at normal incidence and exit in float64, is zero or within
  ``[TINY / EPS, sqrt(HUGE)]``: values down to ``EPS`` of it stay normal, and the peak and the
  Jones products have a factor 1.8e19 of room above it (e.g. a coating of index 1e16 makes the
  facet reflection ``~ (2 / n)^4 ~ 1e-64``, zero in float32).

The sine allowance is float32's own error of ``sqrt(1 - cos^2)`` (``tests/test_float32_domain.py``
checks the 2048 against float32 itself, and the kernels' sines against 1.125 EPS).
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
    "TINY",
    "HUGE",
    "TOLERANCE",
    "SINE",
    "ARITHMETIC",
    "ANGLE_ROWS",
    "condition",
    "unsafe",
    "model_unsafe",
]

_F32 = np.finfo(np.float32)
EPS = float(_F32.eps)
TINY = float(_F32.tiny)
HUGE = float(_F32.max)
#: the float32 error (``E`` above) the domain admits: two digits of the model's peak
TOLERANCE = 1e-2
#: the kernels' rounding and the polar angles' (in units of EPS)
ARITHMETIC = 256.0
#: the sine error the domain charges: that of ``sqrt(1 - cos^2)`` near normal incidence in float32
#: (the kernels' own sines are within 1.125 EPS; see the module docstring)
SINE = math.sqrt(EPS / 2.0)
_S = SINE / EPS

_GAUSS_L = math.sqrt(2.0 / math.e)
_COS89 = math.cos(math.radians(89.0))
#: ``max |P'(u)| / P(0)`` of each slope kind's density (unit width)
LOBE_SLOPE = {
    EXPONENTIAL: math.sqrt(6.0),
    ANISO_EXPONENTIAL: math.sqrt(6.0),
    GAUSSIAN: _GAUSS_L,
    ANISO_GAUSSIAN: _GAUSS_L,
    STROKE: _GAUSS_L,
    GGX: 4.0 / math.sqrt(5.0) * (5.0 / 6.0) ** 3,
    ANISO_GGX: 4.0 / math.sqrt(5.0) * (5.0 / 6.0) ** 3,
}
#: parameter rows that are angles: the float32 rows take them reduced to (-pi, pi] in float64
#: (:class:`scatterbench.models.kernels.Compiled`), so any finite value is exact enough
ANGLE_ROWS = ("rotation", "stroke_angle")
#: rows holding an angle's cosine or sine: in [-1, 1], where rounding to float32 (to zero
#: below 1.2e-38) is the angle's own rounding
TRIG_ROWS = ("stroke_cos", "stroke_sin")
#: kernels that compute sines as sqrt(1 - cos^2)
_SINES_FROM_COSINES = ("facet", "maxwell", "cook", "single")


def _index_terms(rows):
    """The relative index's terms (facet, Maxwell-Beard, Cook-Torrance rows)."""
    pec = rows["substrate_re"] == math.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.where(pec, 2.0, rows["substrate_re"] + 1j * rows["substrate_im"]) / rows["coating"]
        m2 = m * m
        d = np.abs(m2 - np.clip(m2.real, 0.0, 1.0))
        w = np.minimum(math.sqrt(2.0 / EPS), 1.0 / np.sqrt(d))
        c_c = np.sqrt(np.maximum(1.0 - m2.real, 0.0))
        near_one = 4.0 * np.abs(m) / np.abs(m - 1.0)
        critical = 4.0 * w / np.maximum(c_c, np.sqrt(d)) + w / np.abs(m2)
        out = {"relative index near 1": near_one, "critical angle": critical}
        return {k: np.where(pec | (m == 1.0), 0.0, v) for k, v in out.items()}


def _coating_term(n):
    """Coating ``n`` near 1 at grazing incidence (0 for ``n = 1`` exactly)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(n == 1.0, 0.0, 2.0 * n * n / (n * n - 1.0 + _COS89**2))


def _width_term(kind, sx, sy):
    slope = LOBE_SLOPE.get(kind, 0.0)  # UnitSlopes: no width
    return slope * _S / np.minimum(sx, sy)


def _facet(rows, iopt):
    out = _index_terms(rows)
    out["lobe width"] = _width_term(int(iopt[0]), rows["sx"], rows["sy"])
    out["coating near 1"] = _coating_term(rows["coating"])
    return out


def _maxwell(rows, iopt):
    out = _facet(rows, iopt)
    out["Maxwell-Beard tau, Omega"] = 2.0 * _S * (1.0 / rows["tau"] + 1.0 / rows["omega"])
    return out


def _cook(rows, iopt):
    out = _index_terms(rows)
    out["lobe width"] = _GAUSS_L * _S / np.minimum(rows["m_parallel"], rows["m_perpendicular"])
    out["coating near 1"] = _coating_term(rows["coating"])
    return out


def _single(rows, iopt):
    a = np.abs(rows["g"])
    gap = 1.0 - a
    return {
        "phase g near +-1": 12.0 / (gap * gap) + 0.75 * np.sqrt(a) * _S / gap,
        "coating near 1": _coating_term(rows["coating"]),
    }


def _btdf(rows, iopt):
    n = rows["substrate"]
    w = np.minimum(rows["sx"], rows["sy"])
    slope = LOBE_SLOPE.get(int(iopt[0]), 0.0)
    with np.errstate(divide="ignore"):
        ratio = np.where(n == 1.0, 0.0, (n + 1.0) / (n - 1.0))
    wide = 16.0 * np.maximum(rows["sx"], rows["sy"]) if slope else 0.0
    return {
        "index near 1": 4.0 * ratio,
        "lobe width": ratio * (2.0 * slope / w + wide),
    }


_TERMS = {
    "facet": _facet,
    "maxwell": _maxwell,
    "cook": _cook,
    "single": _single,
    "btdf": _btdf,
    "diffuse": lambda rows, iopt: {"coating near 1": _coating_term(rows["coating"])},
}


def condition(code, rows, iopt):
    """``(kappa, terms)``: the float32 condition number of each element (the float32 error is
    at most ``EPS * kappa`` of the model's peak, see the module docstring) and its terms by name.

    Parameters
    ----------
    code : str
        The kernel (:data:`scatterbench.models.kernels.drive.CODES`).
    rows : dict
        The kernel's parameter rows by name (:data:`scatterbench.models.kernel_specs.KERNEL_ROWS`), flat float64
        arrays of one length.
    iopt : sequence of int
        The kernel's options.
    """
    terms = {"arithmetic": np.full(len(next(iter(rows.values()))), ARITHMETIC)}
    if code in _SINES_FROM_COSINES:
        terms["sines near normal incidence"] = np.full_like(terms["arithmetic"], 4.0 * _S)
    terms.update({k: np.asarray(v, dtype=float) for k, v in _TERMS[code](rows, iopt).items()})
    kappa = sum(terms.values())
    return kappa, terms


def _unrepresentable(rows):
    """The first parameter row float32 cannot carry (a sentence), or ``None``."""
    for name, v in rows.items():
        if name in ANGLE_ROWS or name in TRIG_ROWS:
            continue
        a = np.abs(v)
        exact_inf = (a == math.inf) & name.startswith("substrate")
        bad = ~exact_inf & ~((a == 0) | ((a >= TINY) & (a <= math.sqrt(HUGE))))
        if np.any(bad):
            x = v[np.argmax(bad)]
            return (
                f"parameter {name} = {x!r} is not a float32 number the kernels can square "
                f"(zero or within [{TINY:.3g}, {math.sqrt(HUGE):.3g}])"
            )
    return None


def unsafe(model, code, rows, iopt):
    """Why ``model`` (whose kernel is ``code`` with parameter ``rows`` by name, flat arrays,
    and options ``iopt``) lies outside the float32-safe domain (a sentence), or ``None``."""
    bad = _unrepresentable(rows)
    if bad is not None:
        return bad
    kappa, terms = condition(code, rows, iopt)
    k = int(np.argmax(kappa))
    if not kappa[k] <= TOLERANCE / EPS:
        name = max(terms, key=lambda t: terms[t][k])
        return (
            f"float32 error bound EPS * kappa = {EPS * kappa[k]:.3g} of the peak exceeds {TOLERANCE:g} "
            f"(largest term: {name}, kappa {terms[name][k]:.3g})"
        )
    scale = np.abs(np.asarray(model.brdf(0.0, 0.0, 0.0), dtype=float)).reshape(-1)
    off = (scale != 0) & ~((scale >= TINY / EPS) & (scale <= math.sqrt(HUGE)))
    if np.any(off):
        return (
            f"the model's scale (M00 at normal incidence {scale[np.argmax(off)]:.3g} 1/sr) is outside "
            f"[{TINY / EPS:.3g}, {math.sqrt(HUGE):.3g}], where float32 keeps every digit of the result"
        )
    return None


def model_unsafe(model):
    """:func:`unsafe` of a model a kernel covers (``model._kernel_spec()`` not ``None``): its
    kernel rows broadcast over a model set's elements."""
    return unsafe(model, *named_rows(model))
