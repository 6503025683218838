"""Smith-shadowed FacetBRDF against Mitsuba 3's ``roughconductor`` (committed data;
no Mitsuba at test time: ``references/scripts/make_mitsuba_roughconductor.py``).

Conventions of the comparison
-----------------------------
* Directions.  Mitsuba's local frame has the normal along +z, as ours.  Its
  ``si.wi`` (towards the detector) is our reflected direction; its ``wo``
  (towards the light in radiance mode) is the reverse of our incident ray,
  ``(-sin ti, 0, cos ti)``.  Both point away from the surface.  The stored
  angles are those of the float32 vectors Mitsuba was given.
* Value.  ``eval`` returns ``f * cos`` of ``wo``: ``f cos(theta_i)`` here (the
  BRDF is reciprocal, so for the unpolarized value the choice of cosine is the
  only thing the direction mapping decides).
* Distributions.  ``ggx`` with ``alpha`` is :class:`scatterbench.models.GGXSlopes` (alpha);
  ``beckmann`` is :class:`scatterbench.models.GaussianSlopes` with ``sigma = alpha``.
  Mitsuba's ``G`` is the separable Smith ``G1(wi) G1(wo)``: exact for GGX, and
  for Beckmann the rational approximation ``G1 = (3.535 a + 2.181 a^2) / (1 +
  2.276 a + 2.577 a^2)`` (``a = 1 / (alpha tan theta)``, 1 for ``a >= 1.6``),
  which differs from the exact erf form by < 0.35 % per ``G1`` (Mitsuba's
  comment; 0.313 % measured below), so by up to 0.63 % for ``G``.
* Fresnel.  Mitsuba's conductor ``eta + i k`` is our ``substrate`` (same sign
  of ``k``), unpolarized reflectance ``(|r_s|^2 + |r_p|^2) / 2``.
* Stokes frames (polarized variant).  Mitsuba states a Stokes vector for a ray
  travelling along ``k`` in the frame ``x = mitsuba.mueller.stokes_basis(k)``
  (stored with the data), ``y = k x x``.  With ``psi`` the angle from our ``s``
  to ``x`` towards our ``p`` (``{s, p, k}`` right-handed), a Stokes vector
  changes as ``S_mitsuba = L(psi) D S_ours`` with ``L`` the rotation of
  ``(Q, U)`` by ``2 psi`` and ``D = diag(1, 1, 1, -1)``: measured here, Mitsuba's
  ``V`` has the opposite sign to ours (its circular handedness / phase
  convention), ``Q`` and ``U`` agree once the frames are aligned.  In the plane
  of incidence Mitsuba's ``x`` is our ``p``, so there ``Q_mitsuba = -Q`` (the
  DESIGN.md remark).  ``M_ours = D L(psi_out)^-1 M_mitsuba L(psi_in) D``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models.geometry import incident_direction, scattered_direction, sp_basis
from scatterbench.models.shadowing import lambda_gaussian, smith_g

# GGX against Mitsuba's float32 variants: issue 15's acceptance, "to float32 precision (<= 2e-5
# relative)", kept as the issue states it. Measured on the committed data (150 rows per variant:
# each row's _ours against the stored value): unpolarized max 1.64e-6 (scalar_rgb; median 2.0e-7),
# 1.58e-6 (polarized, also per Mueller element relative to M00 after the basis change); Beckmann
# with Mitsuba's rational G1 substituted 4.3e-6. float32 eps is 1.19e-7: the worst is ~14 eps, the
# accumulated rounding of Mitsuba's few dozen float32 operations (D, two G1, complex Fresnel,
# cosines) on float32 directions; 2e-5 is ~170 eps, so it is the figure, not a tight bound
# (real errors are far above: no shadowing > 100x it, Beckmann's G1 approximation 5.7e-3).
GGX_TOL = 2e-5


def _mitsuba_g1_beckmann(a):
    """Mitsuba's rational Beckmann G1 at ``a = cot(theta) / alpha``."""
    a = np.asarray(a, dtype=float)
    return np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))


def _approximation_error():
    """sup |G1_mitsuba / G1_exact - 1| over a fine grid of ``a`` (measured: 3.13e-3)."""
    a = np.linspace(1e-4, 1.6, 200001)
    exact = 1.0 / (1.0 + lambda_gaussian(a, 1.0))
    return float(np.max(np.abs(_mitsuba_g1_beckmann(a) / exact - 1.0)))


# Mitsuba's Beckmann G = G1(i) G1(o), each G1 within the rational approximation's
# error e of the exact one, so the two differ by at most (1 + e)^2 - 1 (e = 3.13e-3
# measured: 6.27e-3).  The bound is derived, not chosen: the committed data set reaches
# 5.7e-3, an earlier uniform-angle draw 6.17e-3, both within it.
BECKMANN_TOL = (1.0 + _approximation_error()) ** 2 - 1.0


def test_mitsubas_beckmann_g1_is_within_its_stated_error():
    """Mitsuba's comment says < 0.35 % per G1; so it is, and it is not exact (> 1e-3)."""
    assert 1e-3 < _approximation_error() < 3.5e-3


D = np.diag([1.0, 1.0, 1.0, -1.0])


@pytest.fixture(scope="module")
def data():
    return references.mitsuba_roughconductor()


def _slopes(dist, alpha):
    return models.GGXSlopes(alpha=alpha) if dist == "ggx" else models.GaussianSlopes(sigma=alpha)


def _ours(data, j, shadowing="smith"):
    m = models.FacetBRDF(
        slopes=_slopes(data["distribution"][j], data["alpha"][j]),
        substrate=complex(data["eta"][j], data["k"][j]),
        shadowing=shadowing,
    )
    ti, tr, pr = data["theta_i"][j], data["theta_r"][j], data["phi_r"][j]
    return m.mueller(ti, tr, pr) * math.cos(ti)


def _rows(data, variant, dist):
    return np.flatnonzero((data["variant"] == variant) & (data["distribution"] == dist))


# Mitsuba's float32 exp() underflows below 1.2e-38 and the densities' prefactors lift
# that to ~1e-27 here: below TINY its values are compared only in that ours are too.
TINY = 1e-20


def _rel(a, b):
    """Relative difference; where Mitsuba's float32 value is below TINY, 0 if ours is too."""
    if abs(b) < TINY:
        return 0.0 if abs(a) < TINY else math.inf
    return abs(a - b) / abs(b)


@pytest.mark.parametrize("variant", ["scalar_rgb", "scalar_spectral_polarized"])
@pytest.mark.parametrize("dist, tol", [("ggx", GGX_TOL), ("beckmann", BECKMANN_TOL)])
def test_unpolarized_agreement(data, variant, dist, tol):
    """GGX to float32 precision, Beckmann to Mitsuba's approximation of G1."""
    rows = _rows(data, variant, dist)
    rel = [_rel(_ours(data, j)[0, 0], data["value"][j]) for j in rows]
    assert len(rows) >= 100
    assert max(rel) <= tol


def test_beckmann_difference_is_mitsubas_g1_alone(data):
    """With Mitsuba's rational G1 in place of the exact one, Beckmann agrees to float32
    precision too: the whole Beckmann difference is the approximation, nothing else."""
    worst = 0.0
    for j in _rows(data, "scalar_rgb", "beckmann"):
        a, ti, tr = data["alpha"][j], data["theta_i"][j], data["theta_r"][j]
        sl = models.GaussianSlopes(sigma=a)
        g_exact = smith_g(
            "smith", sl, (math.cos(ti), math.sin(ti), -1.0, 0.0), (math.cos(tr), math.sin(tr), 1, 0)
        )
        g_mi = _mitsuba_g1_beckmann(1 / (a * math.tan(ti))) * _mitsuba_g1_beckmann(1 / (a * math.tan(tr)))
        worst = max(worst, _rel(_ours(data, j)[0, 0] * g_mi / g_exact, data["value"][j]))
    assert worst <= GGX_TOL


def test_without_shadowing_disagrees(data):
    """The comparison can fail: the unshadowed model is off by far more than float32."""
    rows = _rows(data, "scalar_rgb", "ggx")
    rel = [_rel(_ours(data, j, "none")[0, 0], data["value"][j]) for j in rows]
    assert max(rel) > 100 * GGX_TOL


def _stokes_change(k, x):
    """``L(psi)``: our Stokes (right-handed ``{s, p, k}``) to Mitsuba's frame ``x, k x x``."""
    s, p = sp_basis(k)
    psi = math.atan2(x @ p, x @ s)
    c, sn = math.cos(2 * psi), math.sin(2 * psi)
    return np.array([[1, 0, 0, 0], [0, c, sn, 0], [0, -sn, c, 0], [0, 0, 0, 1.0]])


def _in_our_frames(data, j):
    ti, tr, pr = data["theta_i"][j], data["theta_r"][j], data["phi_r"][j]
    k_in, k_out = incident_direction(ti), scattered_direction(tr, pr)
    l_in = _stokes_change(k_in, data["x_in"][j])
    l_out = _stokes_change(k_out, data["x_out"][j])
    return D @ np.linalg.inv(l_out) @ data["mueller"][j] @ l_in @ D


@pytest.mark.parametrize("dist, tol", [("ggx", GGX_TOL), ("beckmann", BECKMANN_TOL)])
def test_polarized_agrees_after_the_basis_change(data, dist, tol):
    """Every Mueller element, relative to M00, after the change of Stokes frames."""
    worst = 0.0
    for j in _rows(data, "scalar_spectral_polarized", dist):
        ours = _ours(data, j)
        if data["mueller"][j][0, 0] < TINY:
            assert ours[0, 0] < TINY
            continue
        worst = max(worst, np.max(np.abs(_in_our_frames(data, j) - ours)) / ours[0, 0])
    assert worst <= tol


def test_polarized_frames_as_stated(data):
    """In the plane of incidence Mitsuba's incident x axis is our p (so Q flips sign), and
    without the V flip the comparison fails."""
    rows = _rows(data, "scalar_spectral_polarized", "ggx")
    j = rows[np.argmax(np.abs(data["mueller"][rows, 2, 3]) + np.abs(data["mueller"][rows, 0, 1]))]
    ti = data["theta_i"][j]
    _, p = sp_basis(incident_direction(ti))
    assert abs(abs(data["x_in"][j] @ p) - 1.0) < 1e-6
    ours = _ours(data, j)
    assert np.max(np.abs(D @ _in_our_frames(data, j) @ D - ours)) > 1e3 * GGX_TOL * ours[0, 0]
