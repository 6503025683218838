"""Detector aperture: projected-solid-angle average, analyzer basis carried over the cone."""

import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models.geometry import scattered_direction, sp_basis, sp_basis_angles
from scatterbench.models.polarization import is_physical, jones_to_mueller

FACET = models.FacetBRDF(slopes=models.GaussianSlopes(0.05), substrate=1.37 + 7.62j)


def _brute(model, ti, tr, pr, aperture, n):
    """Independent route: midpoint rule in (polar offset, azimuth) over the cone, and the
    scattered field projected in 3-D onto the nominal analyzer axes carried to each
    direction (no rotation angle); weights cos(theta) dOmega."""
    kr = scattered_direction(tr, pr)
    s_r, p_r = sp_basis_angles(tr, pr)
    half = 0.5 * aperture
    u = (np.arange(n) + 0.5) / n * half
    chi = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    U, C = (a.ravel() for a in np.meshgrid(u, chi, indexing="ij"))
    k = np.cos(U)[:, None] * kr + np.sin(U)[:, None] * (np.cos(C)[:, None] * p_r + np.sin(C)[:, None] * s_r)
    J = model.jones(ti, np.arccos(np.clip(k[:, 2], -1, 1)), np.arctan2(k[:, 1], k[:, 0]))
    s_k, p_k = sp_basis(k)
    sa = s_r - (k @ s_r)[:, None] * k
    sa /= np.linalg.norm(sa, axis=1)[:, None]
    pa = np.cross(k, sa)
    Jn = np.empty_like(J)
    for col in (0, 1):  # s in, p in
        E = J[:, 0, col][:, None] * s_k + J[:, 1, col][:, None] * p_k
        Jn[:, 0, col] = np.sum(E * sa, axis=1)
        Jn[:, 1, col] = np.sum(E * pa, axis=1)
    w = np.sin(U) * np.maximum(k[:, 2], 0.0)
    return np.einsum("nij,n->ij", jones_to_mueller(Jn), w) / w.sum()


@pytest.mark.parametrize("tr, pr", [(0.0, 0.0), (0.01, 1.0), (0.5, 0.3), (1.0, 0.0)])
def test_matches_an_independent_field_projection_including_the_normal(tr, pr):
    ap = models.DetectorAperture(model=FACET, aperture=math.radians(20.0), resolution=16)
    a = ap.mueller(0.4, tr, pr)
    b1, b2 = (_brute(FACET, 0.4, tr, pr, math.radians(20.0), n) for n in (200, 400))
    b = (4 * b2 - b1) / 3  # the midpoint rule is second order: Richardson
    assert np.max(np.abs(a - b)) / b[0, 0] < 1e-7
    # and re-expressing each direction's matrix in the analyzer basis matters: averaging the
    # matrices in their own bases is wrong by far more than the tolerance (most near the normal)
    k, w = ap.directions(np.atleast_1d(tr), np.atleast_1d(pr))
    M = FACET.mueller(0.4, np.arccos(k[0, :, 2]), np.arctan2(k[0, :, 1], k[0, :, 0]))
    naive = np.einsum("kij,k->ij", M, w[0]) / w[0].sum()
    assert np.max(np.abs(naive - b)) / b[0, 0] > 1e-3


def test_lambertian_reads_its_own_brdf_for_any_aperture_and_nominal_direction():
    lam = models.DiffuseSubsurfaceBRDF(coating=1.0, rho=1.0)  # 1/pi, unpolarized, everywhere
    tr = np.radians([0.0, 30.0, 80.0, 89.9, 90.0])
    for deg in (0.7, 10.0, 90.0):
        ap = models.DetectorAperture(model=lam, aperture=math.radians(deg))
        np.testing.assert_allclose(ap.brdf(0.3, tr, 0.2), 1.0 / math.pi, rtol=1e-13)


def test_converges_fast_in_resolution_and_second_order_in_the_aperture():
    ti, tr, pr = math.radians(60.0), math.radians(61.0), 0.0
    ref = models.DetectorAperture(model=FACET, aperture=math.radians(2.0), resolution=32).brdf(ti, tr, pr)
    err = [
        abs(
            models.DetectorAperture(model=FACET, aperture=math.radians(2.0), resolution=r).brdf(ti, tr, pr)
            - ref
        )
        for r in (1, 2, 4)
    ]
    assert err[0] > err[1] > err[2] and err[2] / ref < 1e-7
    f0 = FACET.brdf(ti, tr, pr)
    dev = [
        abs(
            models.DetectorAperture(model=FACET, aperture=math.radians(a), resolution=8).brdf(ti, tr, pr) - f0
        )
        for a in (1.0, 0.5)
    ]
    assert 3.8 < dev[0] / dev[1] < 4.2  # a smooth lobe: the bias is quadratic in the aperture
    assert math.isclose(
        models.DetectorAperture(model=FACET, aperture=0.0).brdf(ti, tr, pr), f0, rel_tol=1e-14
    )


def test_a_hair_of_aperture_is_the_model_itself_at_the_normal_for_every_azimuth():
    """At theta_r = 0 every model states its matrix in the basis s = (-sin phi_r, cos phi_r, 0);
    the analyzer basis must be that one too (not sp_basis's fixed +y along the axis)."""
    m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.1))
    ap = models.DetectorAperture(model=m, aperture=1e-4)
    pr = np.array([0.0, 1.0, 0.5 * math.pi, -2.5])
    a, b = ap.mueller(0.3, 0.0, pr), m.mueller(0.3, 0.0, pr)
    assert np.max(np.abs(a - b)) < 1e-6 * b[0, 0, 0]


def test_result_is_a_physical_mueller_matrix_and_broadcasts():
    ap = models.DetectorAperture(model=FACET, aperture=math.radians(3.0))
    ti = np.radians([10.0, 45.0, 80.0])[:, None]
    tr = np.radians(np.linspace(0.0, 89.0, 7))[None, :]
    M = ap.mueller(ti, tr, 0.3)
    assert M.shape == (3, 7, 4, 4)
    assert all(is_physical(m) for m in M.reshape(-1, 4, 4))


@pytest.mark.parametrize("kw, name", [({"aperture": -0.1}, "aperture"), ({"aperture": 2.0}, "aperture"),
                                      ({"resolution": 0}, "resolution"), ({"model": 3}, "model")])  # fmt: skip
def test_bad_parameters_name_themselves(kw, name):
    args = {"model": FACET, **kw}
    with pytest.raises(ValueError, match=name):
        models.DetectorAperture(**args)


@pytest.mark.parametrize(
    "inner",
    [
        FACET,
        models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.02)),
        models.SubsurfaceFacetBRDF(slopes=models.GaussianSlopes(0.2)),
        models.FacetBRDF(slopes=models.AnisotropicGaussianSlopes(0.05, 0.2, 0.7), substrate=1.5),
        models.DiffuseSubsurfaceBRDF(),
    ],
    ids=lambda m: repr(m)[:40],
)
@pytest.mark.parametrize(
    "deg, resolution", [(1e-158, 2), (1e-6, 2), (0.7, 4), (5.0, 1), (20.0, 9), (90.0, 3)]
)
@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_fast_node_algebra_equals_the_direct_route(inner, deg, resolution, backend, rng):
    """The node algebra from dot products, with the rotation applied to rows 1-2 only, against
    the direct route it replaced (vectors, arctan2, both bases, full 4x4 rotations): within
    1e-12 of M00, on random geometries and the edges (normal, grazing, azimuths +-pi); with
    the numba backend, compiled (models.kernels.aperture), with numpy, the numpy route."""
    ap = models.DetectorAperture(model=inner, aperture=math.radians(deg), resolution=resolution)
    n = 300
    edges = np.array([0.0, 1e-300, 1e-9, 0.5 * math.pi - 1e-9, 0.5 * math.pi])
    tr = np.r_[rng.uniform(0, 0.5 * math.pi, n), edges, edges]
    pr = np.r_[rng.uniform(-4, 4, n), np.full(edges.size, math.pi), np.full(edges.size, -1e-12)]
    ti = rng.uniform(0, 1.5, tr.size)
    with models.backend(backend):
        fast = ap._mueller16(ti, tr, pr)
        direct = ap._mueller16_reference(ti, tr, pr)
    scale = np.where(direct[0] > 0, direct[0], 1.0)
    assert np.max(np.abs(fast - direct) / scale) <= 1e-12


def test_double_angle_of_nodes_near_and_on_the_normal():
    """Jones rotations whose components would underflow when squared are scaled first; a node
    exactly on the normal is in the nominal basis (c, s) = (1, 0)."""
    from scatterbench.models.aperture import _double_angle_scaled

    c = np.array([3e-170, 0.0, -2e-200, 1.0])
    s = np.array([4e-170, 0.0, 0.0, 0.0])
    c2, s2 = _double_angle_scaled(c, s)
    np.testing.assert_allclose(c2, [-7 / 25, 1.0, 1.0, 1.0], rtol=1e-15)
    np.testing.assert_allclose(s2, [24 / 25, 0.0, 0.0, 0.0], rtol=1e-15, atol=0)


def test_the_quadrature_rule_is_shared_and_read_only():
    """Apertures of one size and resolution share one rule (a fit builds the aperture afresh
    for every evaluation), which no caller can alter; other sizes get their own."""
    kw = dict(model=FACET, aperture=math.radians(0.7), resolution=4)
    a, b = models.DetectorAperture(**kw)._nodes, models.DetectorAperture(**kw)._nodes
    assert all(x is y for x, y in zip(a, b, strict=True))
    assert not any(x.flags.writeable for x in a)
    with pytest.raises(ValueError):
        a[3][0] = 0.0
    other = models.DetectorAperture(**{**kw, "aperture": math.radians(2.0)})._nodes
    assert not np.array_equal(other[0], a[0])
