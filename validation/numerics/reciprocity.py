"""Helmholtz reciprocity check usable on any model.

The reversed path of ``(theta_i, theta_r, phi_r)`` swaps the source and the
detector.  In the standard frame (source at azimuth pi) it is evaluated on the
sample rotated about z by ``pi - phi_r`` (``model.rotated``), which brings the
old detector direction to azimuth pi and the old source to azimuth
``-phi_r``: reversed geometry ``(theta_r, theta_i, -phi_r)``.  A rotation about
z maps each ray's s and p vectors to the rotated ray's, so the bases agree.
Models with no preferred azimuth return themselves from ``rotated`` and the
whole check is one vectorized call.

Scalar form: ``f(i -> r) = f(r -> i)``.

Polarized form, derived here.  The reciprocity theorem makes the 3x3
scattering dyadic of the reversed path the transpose of the forward one,
``S(-k_i <- -k_r) = S(k_r <- k_i)^T``.  The bases are ``s = unit(z x k)`` and
``p = k x s``: reversing ``k`` flips ``s`` and keeps ``p``.  With
``J_ab = e_a(out) . S . e_b(in)`` this gives, on ``(E_s, E_p)``,

    J_rev = Z J^T Z,      Z = diag(1, -1),

(``ss``, ``pp`` unchanged; the two cross terms exchanged with a sign change),
up to an overall phase, and for Mueller matrices (any sum of them, so
depolarizing reciprocal models too)

    M_rev = D M^T D,      D = diag(1, 1, -1, 1).

:func:`scatterbench.models.polarization.reciprocal_jones` / ``reciprocal_mueller``
implement the two and are tested against each other on random Jones matrices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scatterbench.models.base import is_isotropic, rotated_set
from scatterbench.models.polarization import reciprocal_jones, reciprocal_mueller

__all__ = [
    "ReciprocityErrors",
    "ReciprocityResult",
    "reciprocity_error",
    "reciprocity_errors",
    "reversed_mueller",
]


@dataclass(frozen=True)
class ReciprocityResult:
    """Largest relative reciprocity violations over the geometries checked."""

    scalar: float  # max |f - f_rev| / max(f, f_rev)
    mueller: float  # max element |M_rev - D M^T D| / M00
    jones: float | None  # max |J_rev - phase Z J^T Z| / sqrt(M00); None if depolarizing
    n: int  # geometries with light in at least one direction


def _reversed(model, ti, tr, pr, method):
    """Evaluate ``method`` ('mueller' or 'jones') on the reversed paths."""
    if is_isotropic(model):
        return getattr(model, method)(tr, ti, -pr)
    turned = rotated_set(model, math.pi - pr)  # every geometry's sample turned, in one call
    if turned is not None:
        return getattr(turned, method)(tr, ti, -pr)
    out = None  # a model whose rotated takes one angle: geometry by geometry
    for idx in np.ndindex(ti.shape):
        v = getattr(model.rotated(math.pi - float(pr[idx])), method)(tr[idx], ti[idx], -pr[idx])
        if out is None:
            out = np.empty(ti.shape + v.shape, dtype=v.dtype)
        out[idx] = v
    return out


def reversed_mueller(model, theta_i, theta_r, phi_r):
    """Mueller BRDF of the reversed paths, in the standard frame."""
    ti, tr, pr = np.broadcast_arrays(*(np.asarray(a, float) for a in (theta_i, theta_r, phi_r)))
    return _reversed(model, ti, tr, pr, "mueller")


@dataclass(frozen=True)
class ReciprocityErrors:
    """Per-geometry relative reciprocity violations (flat arrays, one entry a geometry);
    0 where both directions are dark, NaN where a non-finite value enters."""

    scalar: np.ndarray  # |f - f_rev| / max(f, f_rev)
    mueller: np.ndarray  # max element |M_rev - D M^T D| / M00
    jones: np.ndarray | None  # max |J_rev - phase Z J^T Z| / sqrt(M00); None if depolarizing
    live: np.ndarray  # light in at least one direction
    finite: np.ndarray  # every matrix of both paths finite (Mueller, and Jones if any)


def reciprocity_errors(model, theta_i, theta_r, phi_r, *, mueller=None, jones=None) -> ReciprocityErrors:
    """The relative violations of ``f(i -> r) = f(r -> i)``, ``M_rev = D M^T D`` and (non-depolarizing
    models) ``J_rev = Z J^T Z`` at each geometry, flattened.

    Errors are relative to the larger BRDF of the two paths (``M00``) so they mean the same
    across the dynamic range.  ``mueller`` and ``jones``: the forward matrices when the
    caller already has them (evaluated here otherwise).
    """
    ti, tr, pr = np.broadcast_arrays(*(np.asarray(a, float) for a in (theta_i, theta_r, phi_r)))
    fwd = np.asarray(model.mueller(ti, tr, pr) if mueller is None else mueller).reshape(-1, 4, 4)
    rev = np.asarray(_reversed(model, ti, tr, pr, "mueller")).reshape(-1, 4, 4)
    f1, f2 = fwd[:, 0, 0], rev[:, 0, 0]
    scale = np.maximum(np.abs(f1), np.abs(f2))
    live = scale > 0
    den = np.where(live, scale, 1.0)
    scalar = np.where(live, np.abs(f1 - f2) / den, 0.0)
    full = np.where(live, np.max(np.abs(rev - reciprocal_mueller(fwd)), axis=(-1, -2)) / den, 0.0)
    finite = np.all(np.isfinite(fwd), axis=(-1, -2)) & np.all(np.isfinite(rev), axis=(-1, -2))
    jerr = None
    if not model.depolarizing:
        J = model.jones(ti, tr, pr) if jones is None else jones
        pred = reciprocal_jones(np.asarray(J).reshape(-1, 2, 2)).reshape(-1, 4)
        got = np.asarray(_reversed(model, ti, tr, pr, "jones")).reshape(-1, 4)
        # Jones matrices are defined up to an overall phase: align it first.
        inner = np.sum(pred * np.conj(got), axis=1)
        mag = np.abs(inner)
        phase = np.where(mag > 0, inner / np.where(mag > 0, mag, 1.0), 1.0)
        diff = np.max(np.abs(pred - phase[:, None] * got), axis=1)
        jerr = np.where(live, diff / np.sqrt(den), 0.0)
        finite &= np.all(np.isfinite(pred), axis=1) & np.all(np.isfinite(got), axis=1)
    return ReciprocityErrors(scalar, full, jerr, live, finite)


def reciprocity_error(model, theta_i, theta_r, phi_r) -> ReciprocityResult:
    """Check ``f(i -> r) = f(r -> i)``, ``M_rev = D M^T D`` and (non-depolarizing
    models) ``J_rev = Z J^T Z`` at the given geometries: the largest of
    :func:`reciprocity_errors`.

    Errors are relative to the BRDF at each geometry (``M00``) so they mean
    the same across the dynamic range; geometries dark in both directions are
    skipped.
    """
    e = reciprocity_errors(model, theta_i, theta_r, phi_r)
    if not np.any(e.live):
        return ReciprocityResult(0.0, 0.0, None if model.depolarizing else 0.0, 0)
    jones = None if e.jones is None else float(np.max(e.jones[e.live]))
    return ReciprocityResult(
        float(np.max(e.scalar[e.live])), float(np.max(e.mueller[e.live])), jones, int(e.live.sum())
    )
