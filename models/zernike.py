"""Reciprocal Zernike-polynomial expansion of the Mueller-matrix BRDF.

Koenderink and van Doorn's phenomenological BRDF expansion (J. Opt. Soc. Am. A 15, 2903 (1998)),
extended to the full Mueller matrix by Germer ("Full four-dimensional and reciprocal Mueller
matrix bidirectional reflectance distribution function of sintered polytetrafluoroethylene,"
Applied Optics (2017)): SCATMECH's ``ZernikeExpansion_BRDF_Model``.  Written from SCATMECH's
documentation page ``docs/zernikeexpansion.htm`` (the definitions below) and checked line by line
against its source: ``code/zernikeexpansion.cpp`` (``ZernikeExpansion_BRDF_Model::mueller``: the
normalizations, the lower-triangle signs, ``model_cs = xyxy``), ``code/zernike.cpp``
(``Radial_Zernike_Polynomial``: ``|k|`` in the radial order, zero for odd ``n - |k|``),
``code/jmatrix.cpp`` (``GetBasisVectorsXY``) and ``code/brdf.cpp`` (``BRDF_Model::convert``).
No code was copied.

Definitions (xyxy basis, angles in the sample frame: ``phi_i`` is the azimuth of the direction
toward the source, ``phi_r`` that of the scattered direction, ``rho = sqrt(2) sin(theta / 2)``,
which maps the hemisphere onto the unit disc with equal areas):

* ``R_n^k(rho)``: the radial Zernike polynomial of order ``n`` and ``|k|`` (zero unless
  ``n - |k|`` is even).
* ``az_k(phi) = cos(k phi)`` for ``k > 0``, ``1/sqrt(2)`` for ``k = 0``, ``sin(|k| phi)`` for
  ``k < 0``; ``K_n^k(theta, phi) = sqrt((n + 1) / pi) R_n^k(rho) az_k(phi)``.
* ``f_11 = r sum a_11 lambda^p (1/(2 pi)) sqrt((n+1)(m+1)/A) [R_n^l(rho_i) R_m^l(rho_r) +
  R_m^l(rho_i) R_n^l(rho_r)] cos(l (phi_r - phi_i))``, with ``A = 4`` if ``n = 0`` or
  (``n = m`` and ``l = 0``), else 2 if ``n = m`` or ``l = 0``, else 1, and ``r`` the scale.
* Diagonal ``ii``: ``f_ii / f_11 = sum a lambda^p [K_n^k(i) K_m^l(r) + K_n^k(r) K_m^l(i)] /
  sqrt(2 + 2 delta_nm delta_kl)``.
* Upper ``ij`` (``i < j``): ``f_ij / f_11 = sum a lambda^p K_n^k(i) K_m^l(r)``; lower:
  ``f_ji / f_11 = +- sum a lambda^p K_m^l(i) K_n^k(r)``, with ``-`` for ``31``, ``32`` and
  ``43`` (1-based) and ``+`` otherwise.

Reciprocity holds by construction: swapping the two directions maps each upper term onto its
lower partner, and the signs are those of ``D M^T D`` with ``D = diag(1, 1, -1, 1)``.  It holds
in the psps basis too (the project's check, :func:`scatterbench.validation.reciprocity_error`),
because a ray's xyxy basis depends on the ray and the sample's x axis only, and reversing a ray
flips its first basis vector and keeps its second, as for s and p.

The xyxy basis and the conversion (:func:`scatterbench.models.polarization.xyxy_to_psps`):
up to sign, a ray's xyxy basis is its ``(s, p)`` basis turned by ``-phi_r`` (scattered ray) or
by ``+phi_i`` (incident ray), so ``M_psps = R(-phi_r) M_xyxy R(-phi_i)``.  The azimuths are
the sample-frame ones, the same as the expansion's: this differs from SCATMECH's
``BRDF_Model::convert``, which turns the scattered basis by the azimuth relative to the plane
of incidence whatever ``rotation`` is (the same thing at ``rotation = 0``, where every NIST
measurement lies; see the conventions guide and ``docs/guide/slips.md``).

A coefficient table is a tuple of rows ``(i, j, n, m, k, l, p, a)`` as in SCATMECH's
coefficient files (:func:`scatterbench.references.nist_ptfe_coefficients` loads NIST's).  The
default table, ``((1, 1, 0, 0, 0, 0, 0, 2.0),)``, is an ideal Lambertian depolarizer of unit
albedo (``f_11 = 1/pi``, every other element zero).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .base import Model
from .constraints import FACTOR_MAX, Constraint, Interval, ParameterError, ScalarOrArray
from .facts import Correspondence
from .params import param

__all__ = ["ZernikeExpansionBRDF", "radial_zernike", "check_coefficient_table", "LAMBERTIAN_TABLE"]

#: Highest radial order accepted.  The radial polynomials are evaluated from their explicit
#: coefficients, whose alternating sum loses about ``log10(max coefficient)`` digits: at order 20
#: the largest coefficient is ~1.8e5 (5 digits of 16 lost); NIST's tables stop at order 7.
MAX_ORDER = 20

#: An ideal Lambertian depolarizer of unit albedo: ``f_11 = a / (2 pi) = 1/pi``.
LAMBERTIAN_TABLE = ((1, 1, 0, 0, 0, 0, 0, 2.0),)

#: 0-based (row, column) of the lower-triangle elements whose sign changes under the transpose
#: (31, 32 and 43, 1-based): the elements where ``D M^T D`` differs from ``M^T``.
_FLIPPED = {(2, 0), (2, 1), (3, 2)}


def _radial_coefficients(n, k):
    """Coefficients of ``rho^0 .. rho^n`` of the radial Zernike polynomial ``R_n^|k|``."""
    m = abs(k)
    out = np.zeros(n + 1)
    if (n - m) % 2:
        return out
    for s in range((n - m) // 2 + 1):
        out[n - 2 * s] = (
            (-1) ** s
            * math.factorial(n - s)
            / (math.factorial(s) * math.factorial((n + m) // 2 - s) * math.factorial((n - m) // 2 - s))
        )
    return out


def radial_zernike(n, k, rho):
    """The radial Zernike polynomial ``R_n^|k|(rho)`` (zero for odd ``n - |k|``), any array ``rho``."""
    rho = np.asarray(rho, dtype=float)
    return np.polynomial.polynomial.polyval(rho, _radial_coefficients(int(n), int(k)))


def _row_problem(row):
    """What is wrong with one table row (``None``: nothing), and the row as ints and a float."""
    if not isinstance(row, (tuple, list, np.ndarray)) or len(row) != 8:
        return "must be 8 values (i, j, n, m, k, l, p, a)", None
    try:
        ints = [float(v) for v in row[:7]]
        a = float(row[7])
    except (TypeError, ValueError):
        return "must be numbers", None
    if not all(math.isfinite(v) and v == int(v) for v in ints):
        return "i, j, n, m, k, l and p must be integers", None
    i, j, n, m, k, l, p = (int(v) for v in ints)
    if not math.isfinite(a):
        return "the coefficient a must be finite", None
    if not (1 <= i <= j <= 4):
        return "needs 1 <= i <= j <= 4 (upper triangle; the lower one follows by reciprocity)", None
    if not (0 <= n <= MAX_ORDER and 0 <= m <= MAX_ORDER):
        return f"radial orders n, m must be in [0, {MAX_ORDER}]", None
    if abs(k) > n or abs(l) > m or (n - abs(k)) % 2 or (m - abs(l)) % 2:
        return "needs |k| <= n, |l| <= m with n - |k| and m - |l| even (else R_n^k is zero)", None
    if (i, j) == (1, 1) and (k != l or l < 0):
        return "an 11 term depends on cos(l (phi_r - phi_i)) only: it needs k = l >= 0", None
    if abs(p) > 16:
        return "the power p of lambda must be in [-16, 16]", None
    return None, (i, j, n, m, k, l, p, a)


class CoefficientTable(Constraint):
    """A non-empty sequence of ``(i, j, n, m, k, l, p, a)`` rows (seven integers and a float,
    SCATMECH's coefficient-file lines), returned as a tuple of rows."""

    kind = "sequence"

    def describe(self) -> str:
        return "a non-empty sequence of (i, j, n, m, k, l, p, a) rows"

    def check(self, name, value) -> tuple:
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) == 0:
            self.fail(name, value)
        rows = []
        for index, row in enumerate(value):
            problem, clean = _row_problem(row)
            if problem:
                raise ParameterError(name, self.describe(), f"row {index} ({row!r})", f": {problem}")
            rows.append(clean)
        return tuple(rows)


def check_coefficient_table(name, value):
    """``value`` as a coefficient table, or the ``ValueError`` naming ``name``, the row and the
    allowed range (:class:`CoefficientTable`)."""
    return CoefficientTable().check(name, value)


def _k_index(rows):
    """``{(n, k): index}`` of every ``K_n^k`` a table needs (both ``+-l`` for its 11 terms)."""
    keys = set()
    for i, j, n, m, k, l, _, _ in rows:
        if (i, j) == (1, 1):
            keys |= {(n, l), (n, -l), (m, l), (m, -l)}
        else:
            keys |= {(n, k), (m, l)}
    return {key: u for u, key in enumerate(sorted(keys))}


def _add_11(C, u, n, m, l, a):
    """The 11 term as a bilinear form in ``K``: ``cos(l dphi) = az_l az_l + az_-l az_-l`` (l > 0),
    ``1 = 2 az_0 az_0`` (l = 0), and ``R_n R_m = K_n K_m / (kappa_n kappa_m)``."""
    big_a = 4.0 if (n == 0 or (n == m and l == 0)) else (2.0 if (n == m or l == 0) else 1.0)
    pre = math.sqrt((n + 1) * (m + 1) / big_a) / (2.0 * math.pi)
    w = a * pre / math.sqrt((n + 1) * (m + 1) / math.pi**2)
    for ll in (0,) if l == 0 else (l, -l):
        c = w * (2.0 if l == 0 else 1.0)
        C[u[(n, ll)], u[(m, ll)]] += c  # R_n(i) R_m(r)
        C[u[(m, ll)], u[(n, ll)]] += c  # R_m(i) R_n(r)


def _matrices(rows):
    """``(powers, C, keys)``: ``C[q, e]`` is element ``e``'s (row-major, 0..15) matrix of the
    bilinear form ``K_i^T C K_r`` for the terms with ``lambda^powers[q]``; ``keys`` lists the
    ``(n, k)`` of each ``K`` row."""
    u = _k_index(rows)
    powers = sorted({r[6] for r in rows})
    C = np.zeros((len(powers), 16, len(u), len(u)))
    for i, j, n, m, k, l, p, a in rows:
        Cq = C[powers.index(p)]
        if (i, j) == (1, 1):
            _add_11(Cq[0], u, n, m, l, a)
        elif i == j:
            c = a / math.sqrt(2.0 + 2.0 * (n == m and k == l))
            Cq[4 * (i - 1) + (j - 1), u[(n, k)], u[(m, l)]] += c
            Cq[4 * (i - 1) + (j - 1), u[(m, l)], u[(n, k)]] += c
        else:
            Cq[4 * (i - 1) + (j - 1), u[(n, k)], u[(m, l)]] += a
            sign = -1.0 if (j - 1, i - 1) in _FLIPPED else 1.0
            Cq[4 * (j - 1) + (i - 1), u[(m, l)], u[(n, k)]] += sign * a
    keys = sorted(u, key=u.get)
    return np.array(powers, dtype=float), C, keys


def _k_coefficients(keys):
    """``(coef, ks)``: row ``u`` of ``coef`` holds ``sqrt((n+1)/pi)`` times the coefficients of
    ``rho^0..rho^top`` of ``R_n^k`` for ``keys[u] = (n, k)``; ``ks`` the ``k`` of each row."""
    top = max(n for n, _ in keys)
    coef = np.zeros((len(keys), top + 1))
    for u, (n, k) in enumerate(keys):
        coef[u, : n + 1] = _radial_coefficients(n, k) * math.sqrt((n + 1) / math.pi)
    return coef, np.array([k for _, k in keys])


def _k_table(coef, ks, theta, phi):
    """``K_n^k(theta, phi)`` ``(U, N)`` for every row of :func:`_k_coefficients`: the radial
    polynomials as one matrix product over the powers of rho (built by repeated products, a
    loop over orders), the azimuthal factors gathered from one cos/sin table per ``|k|``."""
    rho = math.sqrt(2.0) * np.sin(0.5 * theta)
    powers = np.empty((coef.shape[1], rho.size))
    powers[0] = 1.0
    for q in range(1, coef.shape[1]):
        powers[q] = powers[q - 1] * rho
    orders = np.unique(np.abs(ks[ks != 0]))
    kphi = orders[:, None] * phi[None, :]
    table = np.concatenate([np.full((1, rho.size), math.sqrt(0.5)), np.cos(kphi), np.sin(kphi)])
    pos = {int(k): q for q, k in enumerate(orders)}
    rows = [0 if k == 0 else 1 + pos[abs(k)] + (len(orders) if k < 0 else 0) for k in ks]
    return (coef @ powers) * table[rows]


def _bilinear(forms, Ki, Kr):
    """``(16, N)``: ``K_i^T C_e K_r`` per element ``e`` and geometry (``forms`` ``(16, U, U)``).
    One matrix product for all elements (numpy's stacked ``matmul`` of small matrices measured
    16x slower here), then one contraction per element (faster than one einsum over all)."""
    Y = (forms.reshape(-1, forms.shape[-1]) @ Kr).reshape(forms.shape[0], forms.shape[1], -1)
    return np.stack([np.einsum("an,an->n", Ki, Y[e]) for e in range(forms.shape[0])])


def _turned16(m, a_out, a_in):
    """``R(a_out) M R(a_in)`` (:func:`scatterbench.models.polarization.basis_rotation`) on
    element-major ``(16, N)`` storage: the Q and U rows, then the Q and U columns, mixed in
    place of numpy's stacked 4x4 products (slow for small matrices)."""
    M = m.reshape(4, 4, -1).copy()
    c, s = np.cos(2.0 * a_out), np.sin(2.0 * a_out)
    M[1], M[2] = c * M[1] - s * M[2], s * M[1] + c * M[2]
    c, s = np.cos(2.0 * a_in), np.sin(2.0 * a_in)
    M[:, 1], M[:, 2] = c * M[:, 1] + s * M[:, 2], c * M[:, 2] - s * M[:, 1]
    return M.reshape(16, -1)


@dataclass(frozen=True)
class ZernikeExpansionBRDF(Model):
    """Reciprocal Zernike expansion of the Mueller-matrix BRDF (SCATMECH ``ZernikeExpansion_BRDF_Model``).

    Parameters
    ----------
    coefficients : tuple
        The coefficient table: rows ``(i, j, n, m, k, l, p, a)`` as in SCATMECH's coefficient
        files (:func:`scatterbench.references.nist_ptfe_coefficients`).  Default: an ideal
        Lambertian depolarizer of unit albedo.
    wavelength_um : float
        Wavelength in micrometres, for the ``lambda^p`` terms (SCATMECH's ``lambda``).
    scale : float
        Overall factor ``r(lambda)`` (SCATMECH's ``scale``).
    rotation : float
        Azimuth of the sample's x axis (radians): the expansion is evaluated at
        ``phi_i = pi - rotation``, ``phi_r = phi_r - rotation`` (SCATMECH's ``rotation``).

    Notes
    -----
    :meth:`mueller` returns the psps basis (the project's); :meth:`mueller_general` evaluates
    any four-dimensional geometry in either basis.  Polar angles at or beyond 90 deg give zero,
    as SCATMECH's ``BRDF_Model`` does.  A table fitted to measurements is only as good as its
    data's coverage: NIST's PTFE tables were fitted at incidence 0-75 deg in the plane
    ``phi_i = pi`` (``rotation = 0``); elsewhere the expansion extrapolates.
    """

    coefficients: tuple = param(
        LAMBERTIAN_TABLE,
        "coefficient table, rows (i, j, n, m, k, l, p, a) as in SCATMECH's coefficient files",
        CoefficientTable(),
    )
    wavelength_um: float = param(
        0.532,
        "wavelength (micrometres) for the lambda^p terms",
        ScalarOrArray(Interval(0.0, None, closed="right")),
    )
    scale: float = param(
        1.0, "overall factor r(lambda) (SCATMECH's scale)", ScalarOrArray(Interval(0.0, FACTOR_MAX))
    )
    rotation: float = param(
        0.0, "azimuth of the sample's x axis (rad; SCATMECH's rotation)", ScalarOrArray(Interval())
    )

    correspondence = Correspondence(
        "Koenderink & van Doorn (1998) extended to the Mueller matrix by Germer (2017): NIST's PTFE tables",
        "``ZernikeExpansion_BRDF_Model`` (``coefficientfile``, ``scale``; xyxy basis)",
    )

    @property
    def scatmech(self):
        """``None``: SCATMECH's ``ZernikeExpansion_BRDF_Model`` takes its table as a file
        (``coefficientfile``), not as parameters, so the kit's comparison by parameters has no
        equivalent to name; tests/test_zernike.py holds this model to SCATMECH's definition
        term by term instead."""
        return None

    depolarizing = True
    _numpy_sets = True  # the parameters enter as arrays broadcast against the angles

    @cached_property
    def _forms(self):
        powers, C, keys = _matrices(self.coefficients)
        return powers, C, _k_coefficients(keys)

    def rotated(self, angle):
        """The sample turned by ``angle`` about z: ``rotation + angle`` (an array gives a model set)."""
        return self.replace(rotation=self.rotation + np.asarray(angle, dtype=float))

    def _xyxy16(self, ti, phi_i, tr, phi_r):
        """The expansion ``(16, N)`` in the xyxy basis at sample-frame geometries (flat arrays)."""
        powers, C, (coef, ks) = self._forms
        Ki, Kr = _k_table(coef, ks, ti, phi_i), _k_table(coef, ks, tr, phi_r)
        lam = np.asarray(self.wavelength_um, dtype=float)
        if lam.ndim == 0:  # one wavelength: one matrix per element
            out = _bilinear(np.tensordot(lam**powers, C, axes=1), Ki, Kr)
        else:  # a model set over wavelength: each power weighted per geometry
            out = sum(lam**p * _bilinear(C[q], Ki, Kr) for q, p in enumerate(powers))
        f11 = out[0] * self.scale
        out[0] = 1.0
        return out * f11

    def mueller_general(self, theta_i, phi_i, theta_r, phi_r, basis="psps"):
        """The Mueller BRDF ``(..., 4, 4)`` at general geometries, in ``basis`` (``"psps"`` or
        ``"xyxy"``).

        ``phi_i`` is the azimuth of the direction toward the source and ``phi_r`` that of the
        scattered direction, in the sample frame (``rotation`` is not applied); the standard
        geometry of :meth:`mueller` is ``phi_i = pi``.  All four broadcast against each other.
        """
        if basis not in ("psps", "xyxy"):
            raise ValueError(f"basis must be 'psps' or 'xyxy'; got {basis!r}")
        if self.param_shape != ():
            raise ValueError("mueller_general evaluates a single model, not a model set")
        ti, pi_, tr, pr = np.broadcast_arrays(
            *(np.asarray(a, dtype=float) for a in (theta_i, phi_i, theta_r, phi_r))
        )
        self._angles(ti, tr, pr)  # validated as mueller's angles
        self._angles(ti, tr, pi_)
        shape = ti.shape
        m16 = self._evaluate(ti.ravel(), pi_.ravel(), tr.ravel(), pr.ravel(), basis)
        return m16.T.reshape(shape + (4, 4))

    def _evaluate(self, ti, phi_i, tr, phi_r, basis):
        """``(16, N)``: the expansion at sample-frame geometries, zero at grazing, in ``basis``."""
        m = self._xyxy16(ti, phi_i, tr, phi_r)
        if basis == "psps":
            m = _turned16(m, -phi_r, -phi_i)
        grazing = (ti >= 0.5 * math.pi) | (tr >= 0.5 * math.pi)
        return np.where(grazing, 0.0, m)

    def _mueller16(self, ti, tr, pr):
        rot = np.asarray(self.rotation, dtype=float)
        # a turn beyond one revolution reduced exactly (fmod): 2 x 1.79e308 overflowed to inf,
        # and its cosine was NaN (issue 31's contract test); ordinary rotations are untouched
        rot = np.where(np.abs(rot) > 2.0 * math.pi, np.fmod(rot, 2.0 * math.pi), rot)
        return self._evaluate(ti, math.pi - rot + 0.0 * ti, tr, pr - rot, "psps")
