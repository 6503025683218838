"""Jones-to-Mueller map, Stokes conventions, reciprocity relations, realizability."""

import numpy as np
import pytest

from models.polarization import (
    coherency_eigenvalues,
    ellipsometric,
    is_physical,
    jones_to_mueller,
    reciprocal_jones,
    reciprocal_mueller,
    stokes,
    stokes_from_jones_vector,
)


def random_jones(rng, n=50):
    return rng.normal(size=(n, 2, 2)) + 1j * rng.normal(size=(n, 2, 2))


def test_mueller_transforms_stokes_like_jones(rng):
    J = random_jones(rng)
    E = rng.normal(size=(50, 2)) + 1j * rng.normal(size=(50, 2))
    M = jones_to_mueller(J)
    lhs = np.einsum("nij,nj->ni", M, stokes_from_jones_vector(E))
    rhs = stokes_from_jones_vector(np.einsum("nij,nj->ni", J, E))
    np.testing.assert_allclose(lhs, rhs, atol=1e-12)


def test_stokes_conventions():
    np.testing.assert_allclose(stokes_from_jones_vector([1, 0]), [1, 1, 0, 0])  # s: Q = +1
    np.testing.assert_allclose(stokes_from_jones_vector([0, 1]), [1, -1, 0, 0])
    np.testing.assert_allclose(stokes_from_jones_vector(np.array([1, 1]) / np.sqrt(2)), [1, 0, 1, 0])
    assert np.allclose(stokes("linear:45"), [1, 0, 1, 0])
    with pytest.raises(ValueError, match="polarization"):
        stokes("diagonal")
    with pytest.raises(ValueError, match="polarization"):
        stokes([1, 2, 0, 0])


def test_ellipsometric_quantities():
    i, eta, pc, p = ellipsometric(np.array([[2.0, 0.0, 2.0, 0.0], [1.0, 0.0, 0.0, 0.5], [0, 0, 0, 0]]))
    assert eta[0] == pytest.approx(np.pi / 4)
    assert p[0] == pytest.approx(1.0) and pc[0] == 0
    assert pc[1] == pytest.approx(0.5) and p[1] == pytest.approx(0.5)
    assert np.isnan(p[2])  # no light: polarization undefined, never a fake number


def test_reciprocity_jones_and_mueller_agree(rng):
    J = random_jones(rng)
    np.testing.assert_allclose(
        jones_to_mueller(reciprocal_jones(J)), reciprocal_mueller(jones_to_mueller(J)), atol=1e-12
    )
    # an involution
    np.testing.assert_allclose(reciprocal_jones(reciprocal_jones(J)), J)


def test_realizability(rng):
    M = jones_to_mueller(random_jones(rng))
    assert np.all(is_physical(M))
    ev = coherency_eigenvalues(M)
    assert np.all(ev[..., :3] > -1e-12) and np.all(ev[..., 3] > 0)  # rank one: pure
    assert not is_physical(np.diag([1.0, 1.0, 1.0, -1.0]))  # a time reversal is not physical
    assert is_physical(np.diag([1.0, 0.0, 0.0, 0.0]))  # the ideal depolarizer is
