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
import numbers

import numpy as np

from .text import shown

__all__ = [
    "jones_to_mueller",
    "mueller16_from_jones",
    "stokes",
    "stokes_from_jones_vector",
    "ellipsometric",
    "wrap_axis",
    "coherency_matrix",
    "coherency_eigenvalues",
    "is_physical",
    "reciprocal_mueller",
    "reciprocal_jones",
    "basis_rotation",
    "xyxy_to_psps",
    "psps_to_xyxy",
]


def mueller16_from_jones(ss, ps, sp, pp, out=None):
    """Mueller elements ``(16, n)`` (row-major) from Jones elements as ``(re, im)`` pairs.

    ``ps`` is p in, s out; ``sp`` is s in, p out.  Bohren & Huffman's map as
    SCATMECH writes it (``MuellerMatrix(const JonesMatrix&)``), with the complex
    products spelled out in real arithmetic.  Every non-depolarizing model and
    :func:`jones_to_mueller` go through this one map, so the convention lives
    in one place.  ``out`` may be a preallocated ``(16, n)`` array.
    """

    def norm(z):
        return z[0] * z[0] + z[1] * z[1]

    def prod(z, w):  # z * conj(w) as (re, im)
        return z[0] * w[0] + z[1] * w[1], z[1] * w[0] - z[0] * w[1]

    nss, npp, nps, nsp = norm(ss), norm(pp), norm(ps), norm(sp)
    x1r, x1i = prod(ss, ps)
    x2r, x2i = prod(pp, sp)
    x3r, x3i = prod(ss, sp)
    x4r, x4i = prod(pp, ps)
    x5r, x5i = prod(pp, ss)
    x6r, x6i = prod(ps, sp)
    if out is None:
        out = np.empty((16,) + np.shape(nss))
    a = nss + npp
    b = nss - npp
    c = nps + nsp
    d = nsp - nps
    np.add(a, c, out=out[0])
    np.add(b, d, out=out[1])
    np.subtract(b, d, out=out[4])
    np.subtract(a, c, out=out[5])
    out[[0, 1, 4, 5]] *= 0.5
    np.add(x1r, x2r, out=out[2])
    np.subtract(x1i, x2i, out=out[3])
    np.subtract(x1r, x2r, out=out[6])
    np.add(x1i, x2i, out=out[7])
    np.add(x3r, x4r, out=out[8])
    np.subtract(x3r, x4r, out=out[9])
    np.add(x5r, x6r, out=out[10])
    np.add(x5i, x6i, out=out[11])
    np.negative(out[11], out=out[11])
    np.subtract(x4i, x3i, out=out[12])
    np.add(x3i, x4i, out=out[13])
    np.negative(out[13], out=out[13])
    np.subtract(x5i, x6i, out=out[14])
    np.subtract(x5r, x6r, out=out[15])
    return out


def jones_to_mueller(J):
    """Mueller matrix ``(..., 4, 4)`` of Jones matrices ``(..., 2, 2)`` (a single ``(2, 2)``
    matrix gives a ``(4, 4)`` one)."""
    J = np.asarray(J, dtype=complex)
    if J.ndim < 2 or J.shape[-2:] != (2, 2):
        raise ValueError(f"J must be Jones matrices of shape (..., 2, 2); got shape {J.shape}")
    if J.ndim == 2:  # the element arrays are 0-d: the map's out= needs at least one axis
        return jones_to_mueller(J[None])[0]
    parts = [(J[..., a, b].real, J[..., a, b].imag) for a, b in ((0, 0), (0, 1), (1, 0), (1, 1))]
    return np.moveaxis(mueller16_from_jones(*parts), 0, -1).reshape(J.shape[:-2] + (4, 4))


_NAMED = {
    "unpolarized": (1.0, 0.0, 0.0, 0.0),
    "s": (1.0, 1.0, 0.0, 0.0),
    "p": (1.0, -1.0, 0.0, 0.0),
    "+45": (1.0, 0.0, 1.0, 0.0),
    "-45": (1.0, 0.0, -1.0, 0.0),
    "left": (1.0, 0.0, 0.0, 1.0),
    "right": (1.0, 0.0, 0.0, -1.0),
}


_STATES = "one of unpolarized, s, p, +45, -45, left, right, linear:<deg>, or [I, Q, U, V] numbers"


def _refused(what, state):
    return ValueError(f"polarization {what}; got {shown(state)}")


def _is_real(x):
    return isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_))


def stokes(state) -> np.ndarray:
    """A Stokes vector from a name or a 4-vector (a name gives unit intensity).

    Names: ``unpolarized``, ``s``, ``p``, ``+45``, ``-45``, ``left``, ``right``,
    or ``linear:<deg>`` (linear polarization at that finite angle from s toward p).
    A 4-vector ``[I, Q, U, V]`` (a list, tuple or real array) of finite real numbers,
    not bools, with ``I > 0`` and ``Q^2 + U^2 + V^2 <= I^2``.

    Raises
    ------
    ValueError
        Anything else, naming ``polarization`` and what it may be.
    """
    if isinstance(state, str):
        if state.startswith("linear:"):
            try:
                deg = float(state[7:])
            except ValueError:
                deg = math.nan
            if not math.isfinite(deg):
                raise _refused("linear:<deg> needs a finite angle in degrees", state)
            a = math.radians(deg)
            return np.array([1.0, math.cos(2 * a), math.sin(2 * a), 0.0])
        if state not in _NAMED:
            raise _refused(f"must be {_STATES}", state)
        return np.array(_NAMED[state])
    if isinstance(state, np.ndarray):
        real = state.dtype.kind in "iuf"
    else:
        real = isinstance(state, (list, tuple)) and all(_is_real(x) for x in state)
    if not real:
        raise _refused(f"must be {_STATES}", state)
    try:
        v = np.asarray(state, dtype=float)
    except OverflowError:  # an integer no float can hold
        v = np.full(len(state), math.inf)
    if v.shape != (4,) or not np.all(np.isfinite(v)):
        raise _refused("Stokes vector must be 4 finite numbers (I, Q, U, V)", state)
    if v[0] <= 0 or np.sqrt(v[1] ** 2 + v[2] ** 2 + v[3] ** 2) > v[0] * (1 + 1e-12):
        raise _refused("Stokes vector needs I > 0 and Q^2 + U^2 + V^2 <= I^2", state)
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
        lit = ok.all()  # light everywhere (a fit's rows): the same values without the masks
        safe = i if lit else np.where(ok, i, 1.0)
        pc, pol = v / safe, np.sqrt(q * q + u * u + v * v) / safe
    if not lit:
        pc, pol = np.where(ok, pc, np.nan), np.where(ok, pol, np.nan)
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


def wrap_axis(angle):
    """An axis angle (radians) wrapped to (-pi/2, pi/2]: the principal angle ``eta`` is
    defined modulo pi (an axis, not a direction), so differences and noisy values of
    it are compared after this wrap."""
    return 0.5 * np.angle(np.exp(2j * np.asarray(angle, dtype=float)))


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


def basis_rotation(alpha):
    """Mueller matrix ``(..., 4, 4)`` that restates a Stokes vector given in a basis ``(e1, e2)``
    turned by ``alpha`` (radians) about the propagation direction, ``e1 = cos(alpha) s +
    sin(alpha) p``, ``e2 = -sin(alpha) s + cos(alpha) p``, in ``(s, p)``: ``S_sp = R S_e``.

    The field components obey ``E_sp = [[c, -s], [s, c]] E_e``, hence ``Q_sp = cos(2 alpha) Q_e -
    sin(2 alpha) U_e`` and ``U_sp = sin(2 alpha) Q_e + cos(2 alpha) U_e``; ``I`` and ``V`` are
    unchanged.  ``R(alpha)^-1 = R(-alpha)``, and ``R`` has period pi (a basis and its negative
    give the same Stokes vector).
    """
    a = np.asarray(alpha, dtype=float)
    c, s = np.cos(2.0 * a), np.sin(2.0 * a)
    R = np.zeros(a.shape + (4, 4))
    R[..., 0, 0] = R[..., 3, 3] = 1.0
    R[..., 1, 1] = R[..., 2, 2] = c
    R[..., 1, 2] = -s
    R[..., 2, 1] = s
    return R


def xyxy_to_psps(M, phi_i, phi_r):
    """Mueller matrices ``(..., 4, 4)`` in SCATMECH's ``xyxy`` basis restated in the ``psps`` basis.

    ``phi_i`` is the azimuth of the direction *toward the source* and ``phi_r`` that of the
    scattered direction, both in the frame whose x axis defines the xyxy basis (radians; the
    standard geometry has ``phi_i = pi``).  SCATMECH's xyxy basis of a ray (``GetBasisVectorsXY``
    in its ``jmatrix.cpp``) is, up to an overall sign, its ``(s, p)`` basis turned by
    ``-phi_r`` for the scattered ray and by ``+phi_i`` for the incident ray, so

        M_psps = R(-phi_r) M_xyxy R(-phi_i)      (R = :func:`basis_rotation`).

    The polar angles do not enter.  At ``phi_i = pi`` the incident factor is the identity and
    ``M_psps = R(-phi_r) M_xyxy``; in-plane (``phi_r = 0`` or ``pi``) the two bases agree.
    """
    M = np.asarray(M, dtype=float)
    return basis_rotation(-np.asarray(phi_r, float)) @ M @ basis_rotation(-np.asarray(phi_i, float))


def psps_to_xyxy(M, phi_i, phi_r):
    """The inverse of :func:`xyxy_to_psps`: ``M_xyxy = R(phi_r) M_psps R(phi_i)``."""
    M = np.asarray(M, dtype=float)
    return basis_rotation(np.asarray(phi_r, float)) @ M @ basis_rotation(np.asarray(phi_i, float))
