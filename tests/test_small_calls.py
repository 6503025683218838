"""The small-call path (models.kernels.Compiled.fast): every input form it takes gives the
general path's result bit for bit, and every bad input still reaches the general path's
error naming the angle."""

import math

import numpy as np
import pytest

from scatterbench import models
from scatterbench.models import evaluation

MODELS = [
    models.FacetBRDF(slopes=models.GaussianSlopes(0.3)),
    models.FacetBTDF(),
    models.SingleScatterBRDF(phase=models.HenyeyGreenstein(0.3, True)),
    models.CookTorranceBRDF(),
]
X = np.linspace(0.1, 1.4, 12)
Y = X[::-1].copy()

#: (theta_i, theta_r, phi_r) in the forms a user passes them
FORMS = {
    "floats": (0.5, 0.6, 0.1),
    "ints": (0, 1, 2),
    "numpy scalars": (np.float64(0.5), np.float64(0.6), np.int64(3)),
    "0-d arrays": (np.array(0.5), np.array(0.6), np.array(0.1)),
    "lists": ([0.5, 0.7], [0.6, 0.2], [0.1, 0.0]),
    "tuple and float": ((0.5, 0.7), 0.6, 0.1),
    "arrays and a float": (X, Y, 0.3),
    "length-1 arrays": (X[:1], Y, np.array([0.3])),
    "integer arrays": (np.array([0, 1]), np.array([1, 0]), np.array([0, 3])),
    "non-contiguous": (X[::2], Y[::2], X[::2]),
    "grid": (X[:, None], Y[None, :5], 0.3),
    "(1, 1) and (n,)": (np.array([[0.5]]), Y, 0.3),
    "2-d arrays": (X.reshape(3, 4), Y.reshape(3, 4), X.reshape(3, 4)),
}


@pytest.mark.parametrize("model", MODELS, ids=lambda m: type(m).__name__)
@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_every_input_form_gives_the_general_paths_result(model, form, precision):
    args = FORMS[form]
    shape, ref16 = model.mueller16(*args, precision=precision)  # always the general path
    ref = evaluation.as_matrices(ref16, shape)
    got = model.mueller(*args, precision=precision)
    assert got.shape == ref.shape == np.broadcast_shapes(*(np.shape(a) for a in args)) + (4, 4)
    assert got.dtype == np.dtype(precision) and np.array_equal(got, ref)
    b = model.brdf(*args, precision=precision)
    assert b.shape == shape and b.dtype == np.dtype(precision) and np.array_equal(b, ref[..., 0, 0])


def test_the_small_path_writes_into_out():
    m = MODELS[0]
    out = np.empty((16, X.size))
    got = m.mueller(X, Y, 0.3, out=out)
    assert np.shares_memory(got, out) and np.array_equal(got, m.mueller(X, Y, 0.3))
    with pytest.raises(ValueError, match="out must have shape"):
        m.mueller(X, Y, 0.3, out=np.empty((16, X.size), dtype=np.float32))
    with pytest.raises(ValueError, match="out must have shape"):
        m.mueller(X, Y, 0.3, out=np.empty((16, 3)))


BAD = [
    (True, "real number"),
    (np.array([True, False]), "real number"),
    ("0.5", "real number"),
    (None, "real number"),
    (0.5 + 0j, "real number"),
    ([0.5, [0.1, 0.2]], "real number"),  # ragged
    (10**400, "real number"),
    (math.nan, "finite"),
    (np.array([0.2, math.inf]), "finite"),
    ([0.2, math.nan], "finite"),
]
POLAR_BAD = [
    (-0.1, r"\[0, pi/2\]"),
    (1.6, r"\[0, pi/2\]"),
    (np.array([0.1, 2.0]), r"\[0, pi/2\]"),
    (2, r"\[0, pi/2\]"),
]
CASES = [
    (name, k, bad, what) for k, name in enumerate(("theta_i", "theta_r")) for bad, what in BAD + POLAR_BAD
]
CASES += [("phi_r", 2, bad, what) for bad, what in BAD]  # any finite azimuth is valid


@pytest.mark.parametrize("name, position, bad, what", CASES, ids=repr)
@pytest.mark.parametrize("call", ["mueller", "brdf", "mueller float32"])
def test_bad_angles_are_refused_naming_the_angle(name, position, bad, what, call):
    m = MODELS[0]
    args = [0.5, 0.6, 0.1]
    args[position] = bad
    method, *precision = call.split()
    kwargs = {"precision": precision[0]} if precision else {}
    with pytest.raises(ValueError, match=f"{name} must .*{what}"):
        getattr(m, method)(*args, **kwargs)


def test_shapes_that_do_not_broadcast_are_refused():
    with pytest.raises(ValueError, match="shape"):
        MODELS[0].mueller(X, Y[:5], 0.3)


def test_more_than_a_chunk_takes_the_general_path():
    m = MODELS[0]
    n = evaluation.KERNEL_CHUNK + 5
    ti = np.linspace(0.0, 1.5, n)
    assert evaluation.small_angles(ti, 0.3, 0.0, evaluation.KERNEL_CHUNK) is None
    got = m.brdf(ti, 0.3, 0.0)
    assert np.array_equal(got[-10:], m.brdf(ti[-10:], 0.3, 0.0))
