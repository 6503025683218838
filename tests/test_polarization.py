"""Jones-to-Mueller map, Stokes conventions, reciprocity relations, realizability."""

import numpy as np
import pytest

from scatterbench.models.polarization import (
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


@pytest.mark.parametrize(
    "state, words",
    [
        ("linear:nan", "finite angle"),
        ("linear:inf", "finite angle"),
        ("linear:1e400", "finite angle"),
        ("linear:abc", "finite angle"),
        ("linear:", "finite angle"),
        ([1, True, 0, 0], "one of"),
        ((True, False, False, False), "one of"),
        (np.array([True, False, False, False]), "one of"),
        ([1, "0", 0, 0], "one of"),
        ([1, None, 0, 0], "one of"),
        ({"I": 1}, "one of"),
        (None, "one of"),
        (1.0, "one of"),
        ([10**400, 0, 0, 0], "4 finite numbers"),
        ([1, 0, 0, float("nan")], "4 finite numbers"),
        ([1, 0, 0], "4 finite numbers"),
        (np.zeros((2, 2)), "4 finite numbers"),
    ],
)
def test_stokes_refuses_what_is_not_a_polarization(state, words):
    """Every refusal names the polarization and what it may be; none returns NaN."""
    with pytest.raises(ValueError, match="polarization") as exc:
        stokes(state)
    assert words in str(exc.value)


def test_stokes_takes_names_angles_and_real_vectors():
    np.testing.assert_allclose(stokes("linear:90"), [1, -1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(stokes("linear:0"), [1, 1, 0, 0])
    for v in ([2, 0, 0, 1], (2.0, 0.0, 0.0, 1.0), np.array([2, 0, 0, 1]), [np.float32(2), 0, 0, np.int64(1)]):
        np.testing.assert_array_equal(stokes(v), [2.0, 0.0, 0.0, 1.0])


def test_a_model_refuses_a_nan_incident_angle():
    """``scattered_stokes`` goes through :func:`stokes`: no all-NaN result from 'linear:nan'."""
    from scatterbench import models

    with pytest.raises(ValueError, match="polarization linear:<deg>"):
        models.FacetBRDF().scattered_stokes(0.5, 0.5, 0.0, "linear:nan")


def test_ellipsometric_quantities():
    i, eta, pc, p = ellipsometric(np.array([[2.0, 0.0, 2.0, 0.0], [1.0, 0.0, 0.0, 0.5], [0, 0, 0, 0]]))
    assert eta[0] == pytest.approx(np.pi / 4)
    assert p[0] == pytest.approx(1.0) and pc[0] == 0
    assert pc[1] == pytest.approx(0.5) and p[1] == pytest.approx(0.5)
    assert np.isnan(p[2])  # no light: polarization undefined, never a fake number


def test_ellipsometric_with_light_everywhere_gives_the_masked_values(rng):
    """Where every intensity is positive, ellipsometric skips its masks (a fit's rows): the
    same bits as the rows of an input that also holds a dark row, which takes the masks."""
    S = rng.standard_normal((500, 4)) * 10.0 ** rng.uniform(-8, 3, (500, 4))
    S[:, 0] = np.abs(S[:, 0]) + 1e-12
    lit = ellipsometric(S)
    masked = ellipsometric(np.vstack([S, np.zeros(4)]))
    for a, b in zip(lit, masked, strict=True):
        assert np.array_equal(a, b[:-1])
    assert np.isnan(masked[2][-1]) and np.isnan(masked[3][-1])


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
