"""Polarization algebra: Jones to Mueller, Stokes parameters, realizability.

Conventions (DESIGN.md, SCATMECH): Jones matrices act on ``(E_s, E_p)``; a
``(..., 2, 2)`` array ``J`` has ``J[..., 0, 0] = ss``, ``J[..., 0, 1] = ps``
(p in, s out), ``J[..., 1, 0] = sp`` (s in, p out), ``J[..., 1, 1] = pp``.
Stokes vectors are ``(I, Q, U, V)`` with ``I = |E_s|^2 + |E_p|^2``,
``Q = |E_s|^2 - |E_p|^2``, ``U = 2 Re(E_s* E_p)``, ``V = 2 Im(E_s* E_p)``.  The
Jones-to-Mueller map is Bohren & Huffman's as SCATMECH writes it
(``MuellerMatrix(const JonesMatrix&)``).

Seed 000 Sec. 3 quantities: BRDF (``S0`` of the scattered Stokes vector for a
unit incident intensity), the principal angle ``eta = atan2(U, Q) / 2``
(counter-clockwise from s looking into the beam), the degree of circular
polarization ``P_C = V / I`` (positive for left-circular) and the degree of
polarization ``P = sqrt(Q^2 + U^2 + V^2) / I``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "jones_to_mueller",
    "mueller_from_products",
    "stokes",
    "stokes_from_jones_vector",
    "ellipsometric",
    "coherency_matrix",
    "coherency_eigenvalues",
    "is_physical",
    "reciprocal_mueller",
    "reciprocal_jones",
]


def mueller_from_products(nss, npp, nps, nsp, x1, x2, x3, x4, x5, x6, out=None):
    """Assemble Mueller elements from the Hermitian products of a Jones matrix.

    ``nab = |ab|^2`` and the complex products ``x1 = ss ps*``, ``x2 = pp sp*``,
    ``x3 = ss sp*``, ``x4 = pp ps*``, ``x5 = pp ss*``, ``x6 = ps sp*``, each given
    as a ``(re, im)`` pair of real arrays.  Returns (or fills) an array of shape
    ``(16, ...)`` in row-major Mueller order.  Both the generic
    :func:`jones_to_mueller` and the real-arithmetic fast paths of the facet
    models go through this one map, so the convention lives in one place.
    """
    shape = np.shape(nss)
    if out is None:
        out = np.empty((16,) + shape)
    (x1r, x1i), (x2r, x2i), (x3r, x3i) = x1, x2, x3
    (x4r, x4i), (x5r, x5i), (x6r, x6i) = x4, x5, x6
    a = nss + npp
    b = nss - npp
    out[0] = 0.5 * (a + nps + nsp)
    out[1] = 0.5 * (b + nsp - nps)
    out[2] = x1r + x2r
    out[3] = x1i - x2i
    out[4] = 0.5 * (b - nsp + nps)
    out[5] = 0.5 * (a - nsp - nps)
    out[6] = x1r - x2r
    out[7] = x1i + x2i
    out[8] = x3r + x4r
    out[9] = x3r - x4r
    out[10] = x5r + x6r
    out[11] = -x5i - x6i
    out[12] = x4i - x3i
    out[13] = -x3i - x4i
    out[14] = x5i - x6i
    out[15] = x5r - x6r
    return out


def _cprod(a, b):
    z = a * np.conj(b)
    return z.real, z.imag


def jones_to_mueller(J):
    """Mueller matrix ``(..., 4, 4)`` of Jones matrices ``(..., 2, 2)``."""
    J = np.asarray(J, dtype=complex)
    ss, ps, sp, pp = J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1]
    flat = mueller_from_products(
        np.abs(ss) ** 2,
        np.abs(pp) ** 2,
        np.abs(ps) ** 2,
        np.abs(sp) ** 2,
        _cprod(ss, ps),
        _cprod(pp, sp),
        _cprod(ss, sp),
        _cprod(pp, ps),
        _cprod(pp, ss),
        _cprod(ps, sp),
    )
    return np.moveaxis(flat, 0, -1).reshape(J.shape[:-2] + (4, 4))


_NAMED = {
    "unpolarized": (1.0, 0.0, 0.0, 0.0),
    "s": (1.0, 1.0, 0.0, 0.0),
    "p": (1.0, -1.0, 0.0, 0.0),
    "+45": (1.0, 0.0, 1.0, 0.0),
    "-45": (1.0, 0.0, -1.0, 0.0),
    "left": (1.0, 0.0, 0.0, 1.0),
    "right": (1.0, 0.0, 0.0, -1.0),
}


def stokes(state) -> np.ndarray:
    """A unit-intensity Stokes vector from a name or a 4-vector.

    Names: ``unpolarized``, ``s``, ``p``, ``+45``, ``-45``, ``left``, ``right``,
    or ``linear:<deg>`` (linear polarization at that angle from s toward p).
    """
    if isinstance(state, str):
        if state.startswith("linear:"):
            a = math.radians(float(state.split(":", 1)[1]))
            return np.array([1.0, math.cos(2 * a), math.sin(2 * a), 0.0])
        if state not in _NAMED:
            allowed = ", ".join(sorted(_NAMED)) + ", linear:<deg>"
            raise ValueError(f"polarization must be one of {allowed}; got {state!r}")
        return np.array(_NAMED[state])
    v = np.asarray(state, dtype=float)
    if v.shape != (4,) or not np.all(np.isfinite(v)):
        raise ValueError("polarization Stokes vector must be 4 finite numbers (I, Q, U, V)")
    if v[0] <= 0 or np.sqrt(v[1] ** 2 + v[2] ** 2 + v[3] ** 2) > v[0] * (1 + 1e-12):
        raise ValueError("polarization Stokes vector needs I > 0 and Q^2 + U^2 + V^2 <= I^2")
    return v


def stokes_from_jones_vector(E):
    """Stokes vector(s) ``(..., 4)`` of Jones vectors ``(..., 2)`` = ``(E_s, E_p)``."""
    E = np.asarray(E, dtype=complex)
    s, p = E[..., 0], E[..., 1]
    c = np.conj(s) * p
    return np.stack(
        [np.abs(s) ** 2 + np.abs(p) ** 2, np.abs(s) ** 2 - np.abs(p) ** 2, 2 * c.real, 2 * c.imag],
        axis=-1,
    )


def ellipsometric(S):
    """``(I, eta, P_C, P)`` from Stokes vectors ``(..., 4)`` (seed 000 Sec. 3).

    Where ``I = 0`` (no light reaches that direction) eta, P_C and P are NaN:
    a polarization state of nothing is undefined.  Callers plot or mask them.
    """
    S = np.asarray(S, dtype=float)
    i, q, u, v = S[..., 0], S[..., 1], S[..., 2], S[..., 3]
    eta = 0.5 * np.arctan2(u, q)
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = i > 0
        safe = np.where(ok, i, 1.0)
        pc = np.where(ok, v / safe, np.nan)
        pol = np.where(ok, np.sqrt(q * q + u * u + v * v) / safe, np.nan)
    return i, eta, pc, pol


# Pauli basis matching the Stokes definition above: S_k = Tr(sigma_k E E^dagger).
_PAULI = np.array(
    [
        [[1, 0], [0, 1]],
        [[1, 0], [0, -1]],
        [[0, 1], [1, 0]],
        [[0, -1j], [1j, 0]],
    ],
    dtype=complex,
)
# Mueller element M_ij = Tr(sigma_i J sigma_j J^dagger) / 2; the coherency matrix
# H = (1/4) sum_ij M_ij kron(sigma_i, conj(sigma_j)) is then vec(J) vec(J)^dagger
# up to ordering, so a physical (sum of Jones) Mueller matrix has H >= 0 (Cloude).
_KRON = np.einsum("iab,jcd->ijacbd", _PAULI, np.conj(_PAULI)).reshape(4, 4, 4, 4)


def coherency_matrix(M):
    """Cloude's coherency matrix ``(..., 4, 4)`` (Hermitian) of Mueller matrices."""
    M = np.asarray(M, dtype=float)
    return 0.25 * np.einsum("...ij,ijab->...ab", M.astype(complex), _KRON)


def coherency_eigenvalues(M):
    """Real eigenvalues (ascending) of the coherency matrix of ``M``."""
    return np.linalg.eigvalsh(coherency_matrix(M))


def is_physical(M, rtol=1e-9):
    """True where ``M`` is a non-negative sum of Jones-derived Mueller matrices.

    The coherency eigenvalues must be ``>= -rtol * M00``.
    """
    M = np.asarray(M, dtype=float)
    ev = coherency_eigenvalues(M)
    return ev[..., 0] >= -rtol * np.abs(M[..., 0, 0]) - 1e-300


_RECIP = np.diag([1.0, 1.0, -1.0, 1.0])
_Z = np.diag([1.0, -1.0])


def reciprocal_jones(J):
    """Jones matrix the reciprocity theorem predicts for the reversed path.

    Reversing the path swaps the incident and scattered rays and flips the
    ``s`` vector of each (``s = unit(z x k)`` changes sign with ``k``, ``p = k x s``
    does not); the reciprocity theorem makes the scattering dyadic of the
    reversed path the transpose of the forward one.  In the s/p bases this gives
    ``J_rev = Z J^T Z`` with ``Z = diag(1, -1)``: diagonal elements unchanged,
    the two cross-polarized elements swapped with a sign change.
    """
    J = np.asarray(J)
    return _Z @ np.swapaxes(J, -1, -2) @ _Z


def reciprocal_mueller(M):
    """Mueller form of :func:`reciprocal_jones`: ``M_rev = D M^T D``, ``D = diag(1, 1, -1, 1)``.

    (Applies to sums of Jones-derived Mueller matrices, hence to every
    depolarizing model built from reciprocal elementary processes.)
    """
    M = np.asarray(M)
    return _RECIP @ np.swapaxes(M, -1, -2) @ _RECIP
