"""Properties of measured Mueller-matrix BRDFs: reciprocity, mirror symmetry, noise, realizability.

Measured on :class:`~scatterbench.validation.fitting.mueller_data.MuellerData` (NIST's sintered
PTFE in the tests and the conventions guide).  Every relation is tested between pairs of rows
and judged against the data's own noise level.

Reciprocity (:func:`scatterbench.models.polarization.reciprocal_mueller`): the reversed path of a
row is the row whose source and scattered directions are swapped, ``M_rev = D M^T D``,
``D = diag(1, 1, -1, 1)``, in the psps basis (and equally in xyxy: reversing a ray flips the
first vector of either basis and keeps the second).  *Strict* pairs have the two directions
swapped in the sample frame; for an isotropic sample any rotation about the normal may follow,
and in the standard geometry the partner of ``(theta_i, theta_r, phi_r)`` is ``(theta_r,
theta_i, -phi_r)`` (*isotropic* pairs).  A rotation about z leaves psps matrices unchanged but
not xyxy ones, whose basis is tied to the sample's x axis: isotropic pairs need psps.

Mirror symmetry: an isotropic sample is symmetric under the reflection ``y -> -y`` through the
plane of incidence, which maps ``(theta_i, theta_r, phi_r)`` to ``(theta_i, theta_r, -phi_r)``.
A reflection ``R`` maps cross products to minus the cross product of the images, so the
mirrored ray ``R k`` has ``s' = unit(z x R k) = -R s`` and ``p' = R k x s' = R p``: a field
``E_s s + E_p p`` becomes ``-E_s s' + E_p p'``.  Its Stokes vector keeps ``I`` and ``Q`` and
changes the sign of ``U = 2 Re(E_s* E_p)`` and ``V = 2 Im(E_s* E_p)``, so

    M(theta_i, theta_r, -phi_r) = S M(theta_i, theta_r, phi_r) S,   S = diag(1, 1, -1, -1):

the elements 13, 14, 23, 24, 31, 32, 41, 42 are odd in ``phi_r``, the other eight even.  The xyxy
basis obeys the same rule (its first vector also flips sign under the mirror).

Noise (:func:`noise_level`): NIST's scattered directions lie on a square grid of step 0.1 in
``(sin theta_r cos phi_r, sin theta_r sin phi_r)``.  For a smooth function the second difference
``v(x - h) - 2 v(x) + v(x + h)`` along a grid line is noise of variance ``6 sigma^2`` plus the
curvature, so ``sigma = rms(second differences) / sqrt(6)`` (per wavelength, per element;
``log M11`` for M11) is an estimate that the curvature can only inflate.  A pair difference has
variance ``2 sigma^2``: the statistic of a relation is ``chi^2 / dof = mean((difference /
(sqrt(2) sigma))^2)``, near 1 when the relation holds within the noise.

Realizability (:func:`realizability`): the coherency matrix of a physical Mueller matrix is
positive semi-definite (Cloude).  An eigenvalue of ``H(M / M11)`` moves by ``v^H dH v``, whose
standard deviation is at most ``sigma / 2`` for independent element noise ``sigma`` (the 16
matrices ``kron(sigma_i, conj(sigma_j)) / 2`` are orthonormal, so the squared projections of
``v v^H`` on them sum to 1 and ``dH = sum dm_ij kron(...) / 4``).  A matrix whose smallest
eigenvalue is below ``-3 sigma / 2`` is unphysical beyond the noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import spatial

from scatterbench.models.polarization import coherency_eigenvalues, reciprocal_mueller

__all__ = [
    "MIRROR",
    "ODD_ELEMENTS",
    "PairStatistics",
    "Realizability",
    "mirror_pairs",
    "reciprocal_pairs",
    "noise_level",
    "pair_statistics",
    "realizability",
    "Residuals",
    "model_residuals",
]

#: the mirror's Stokes transform, ``diag(1, 1, -1, -1)``
MIRROR = np.diag([1.0, 1.0, -1.0, -1.0])
#: 0-based elements odd in phi_r for a mirror-symmetric sample (13, 14, 23, 24, 31, 32, 41, 42)
ODD_ELEMENTS = tuple((i, j) for i in range(4) for j in range(4) if (i < 2) != (j < 2))


def _matches(A, B, tol):
    """Index pairs ``(a, b)`` with ``|A[a] - B[b]| <= tol``, ``a < b`` (each pair once, no row with
    itself)."""
    found = spatial.cKDTree(A).query_ball_point(B, r=tol)
    pairs = [(a, b) for b, hits in enumerate(found) for a in hits if a < b]
    return np.array(pairs, dtype=int).reshape(-1, 2)


def _per_wavelength(data, key_a, key_b, tol):
    """Pairs of rows at one wavelength with ``key_b`` of the second equal to ``key_a`` of the first."""
    out = []
    for w in np.unique(data.wavelength_nm):
        idx = np.flatnonzero(data.wavelength_nm == w)
        out.append(idx[_matches(key_a[idx], key_b[idx], tol)])
    return np.concatenate(out) if out else np.zeros((0, 2), dtype=int)


def _unit(theta, phi):
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def reciprocal_pairs(data, *, isotropic=True, tol_deg=0.01):
    """Row pairs ``(a, b)`` of the same wavelength that are each other's reversed path.

    ``isotropic=False``: the source and scattered directions swapped in the sample frame (unit
    vectors within ``tol_deg``).  ``isotropic=True``: swapped up to a rotation about the normal,
    i.e. standard geometries ``(theta_i, theta_r, phi_r)`` and ``(theta_r, theta_i, -phi_r)``.
    """
    tol = math.radians(tol_deg)
    if not isotropic:
        src, sca = _unit(data.theta_i, data.phi_i), _unit(data.theta_r, data.phi_r)
        return _per_wavelength(data, np.hstack([src, sca]), np.hstack([sca, src]), tol)
    ti, tr, pr = data.relative_geometry()
    a = np.column_stack([ti, tr, np.cos(pr), np.sin(pr)])
    b = np.column_stack([tr, ti, np.cos(pr), -np.sin(pr)])
    return _per_wavelength(data, a, b, tol)


def mirror_pairs(data, *, tol_deg=0.01):
    """Row pairs ``(a, b)`` of the same wavelength at ``(theta_i, theta_r, +-phi_r)`` (standard
    geometry); rows in the plane of incidence, their own mirror images, are left out."""
    ti, tr, pr = data.relative_geometry()
    a = np.column_stack([ti, tr, np.cos(pr), np.sin(pr)])
    b = np.column_stack([ti, tr, np.cos(pr), -np.sin(pr)])
    return _per_wavelength(data, a, b, math.radians(tol_deg))


def _grid_values(data):
    """``(N, 16)``: ``log M11`` and the 15 normalized elements of each row."""
    N = data.normalized().reshape(len(data), 16)
    return np.column_stack([np.log(data.mueller[:, 0, 0]), N[:, 1:]])


def noise_level(data, step=0.1):
    """``{wavelength_nm: sigma (16,)}``: the noise of M11 (relative) and of each normalized element
    (absolute) from second differences along the lines of the scattering grid of step ``step`` in
    ``sin theta_r (cos phi_r, sin phi_r)`` (see the module docstring).  Rows off the grid are not
    used; a wavelength with no complete triple of grid points is left out."""
    values = _grid_values(data)
    gx = np.sin(data.theta_r) * np.cos(data.phi_r) / step
    gy = np.sin(data.theta_r) * np.sin(data.phi_r) / step
    on = (np.abs(gx - np.round(gx)) < 1e-3) & (np.abs(gy - np.round(gy)) < 1e-3)
    key = np.column_stack(
        [data.wavelength_nm, np.round(np.degrees(data.theta_i), 3), np.round(gx), np.round(gy)]
    )
    row = {tuple(k): r for r, k in enumerate(key) if on[r]}
    out = {}
    for w in np.unique(data.wavelength_nm):
        d2 = []
        for r in np.flatnonzero(on & (data.wavelength_nm == w)):
            lam, t, x, y = key[r]
            for dx, dy in ((1, 0), (0, 1)):
                lo, hi = row.get((lam, t, x - dx, y - dy)), row.get((lam, t, x + dx, y + dy))
                if lo is not None and hi is not None:
                    d2.append(values[lo] - 2.0 * values[r] + values[hi])
        if d2:
            out[float(w)] = np.sqrt(np.mean(np.square(d2), axis=0) / 6.0)
    return out


@dataclass(frozen=True)
class PairStatistics:
    """A relation measured on row pairs: ``n`` pairs; ``rms`` ``(4, 4)``, the rms difference of
    M11 (relative, at ``[0, 0]``) and of each normalized element (absolute); ``ratio`` ``(4, 4)``,
    that rms over the noise's ``sqrt(2) sigma``; ``chi2`` the mean squared normalized difference
    over every pair and element (``chi2_elements``: the 15 normalized elements only)."""

    relation: str
    n: int
    rms: np.ndarray
    ratio: np.ndarray
    chi2: float
    chi2_elements: float


def pair_statistics(data, pairs, relation, noise) -> PairStatistics:
    """``relation`` (``"reciprocity"``: ``N_b = D N_a^T D``; ``"mirror"``: ``N_b = S N_a S``) on
    ``pairs`` of rows of ``data``, judged against ``noise`` (:func:`noise_level`).  Reciprocity
    needs psps data for isotropic pairs (see the module docstring); the caller converts."""
    if relation not in ("reciprocity", "mirror"):
        raise ValueError(f"relation must be 'reciprocity' or 'mirror'; got {relation!r}")
    if len(pairs) == 0:
        raise ValueError("pairs: no pairs to judge the relation on")
    a, b = np.asarray(pairs).T
    N = data.normalized()
    pred = reciprocal_mueller(N[a]) if relation == "reciprocity" else MIRROR @ N[a] @ MIRROR
    diff = (N[b] - pred).reshape(-1, 16)
    f = data.mueller[:, 0, 0]
    diff[:, 0] = np.log(f[b] / f[a])  # M11: relative difference
    sigma = np.stack([noise[float(w)] for w in data.wavelength_nm[a]])
    z = diff / (math.sqrt(2.0) * sigma)
    rms = np.sqrt(np.mean(diff**2, axis=0)).reshape(4, 4)
    ratio = np.sqrt(np.mean(z**2, axis=0)).reshape(4, 4)
    return PairStatistics(relation, len(a), rms, ratio, float(np.mean(z**2)), float(np.mean(z[:, 1:] ** 2)))


@dataclass(frozen=True)
class Realizability:
    """Coherency eigenvalues of the normalized matrices: ``n`` rows, ``unphysical`` of them with
    the smallest eigenvalue below ``-3 sigma / 2`` (their row indices in ``rows``), ``worst``
    (the smallest eigenvalue, in units of M11), ``worst_row`` and ``worst_sigma`` (that row's
    eigenvalue over its noise ``sigma / 2``), ``negative`` rows with any negative eigenvalue."""

    n: int
    negative: int
    unphysical: int
    rows: np.ndarray
    worst: float
    worst_row: int
    worst_sigma: float


def realizability(data, noise) -> Realizability:
    """Cloude's test on every row: a data-quality finding, not a refusal (module docstring)."""
    low = coherency_eigenvalues(data.normalized())[:, 0]
    sigma = np.array([np.mean(noise[float(w)][1:]) for w in data.wavelength_nm]) / 2.0
    beyond = low < -3.0 * sigma
    worst = int(np.argmin(low))
    return Realizability(
        n=len(low),
        negative=int(np.sum(low < 0)),
        unphysical=int(np.sum(beyond)),
        rows=np.flatnonzero(beyond),
        worst=float(low[worst]),
        worst_row=worst,
        worst_sigma=float(low[worst] / sigma[worst]),
    )


@dataclass(frozen=True)
class Residuals:
    """A model against measured rows: ``n`` rows; ``rms`` and ``max`` ``(4, 4)``: of M11 relative
    (``model / measured - 1``, at ``[0, 0]``) and of each normalized element (absolute); with a
    noise level, ``ratio`` ``(4, 4)`` (rms of residual / sigma per element) and ``chi2`` (mean
    squared residual / sigma over rows and elements), else ``None``."""

    n: int
    rms: np.ndarray
    max: np.ndarray
    ratio: np.ndarray | None = None
    chi2: float | None = None

    @property
    def m11_rms(self) -> float:
        return float(self.rms[0, 0])

    @property
    def m11_max(self) -> float:
        return float(self.max[0, 0])


def model_residuals(model, data, noise=None) -> Residuals:
    """``model`` against ``data`` at the rows' own geometries.  A model with ``mueller_general``
    (:class:`scatterbench.models.ZernikeExpansionBRDF`) is evaluated at the sample-frame azimuths
    in the data's basis, one wavelength at a time (``wavelength_um`` set to each); any other model
    at the standard geometry (:meth:`~scatterbench.validation.fitting.mueller_data.MuellerData.relative_geometry`,
    an isotropic sample) against the data in psps.  ``noise``: :func:`noise_level`'s, for the
    ratios."""
    if hasattr(model, "mueller_general"):
        M = np.empty_like(data.mueller)
        for w in np.unique(data.wavelength_nm):
            sel = data.wavelength_nm == w
            m = model.replace(wavelength_um=float(w) / 1000.0)
            M[sel] = m.mueller_general(
                data.theta_i[sel], data.phi_i[sel], data.theta_r[sel], data.phi_r[sel], data.basis
            )
        measured = data
    else:
        measured = data.in_basis("psps")
        M = model.mueller(*measured.relative_geometry())
    diff = (M / M[:, :1, :1] - measured.normalized()).reshape(-1, 16)
    diff[:, 0] = M[:, 0, 0] / measured.mueller[:, 0, 0] - 1.0
    rms = np.sqrt(np.mean(diff**2, axis=0)).reshape(4, 4)
    worst = np.max(np.abs(diff), axis=0).reshape(4, 4)
    if noise is None:
        return Residuals(len(diff), rms, worst)
    z = diff / np.stack([noise[float(w)] for w in data.wavelength_nm])
    ratio = np.sqrt(np.mean(z**2, axis=0)).reshape(4, 4)
    return Residuals(len(diff), rms, worst, ratio, float(np.mean(z**2)))
