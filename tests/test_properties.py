"""Property tests over the parameter space (hypothesis): reciprocity, M00 >= 0, realizability."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from scatterbench import models
from scatterbench.models.polarization import coherency_eigenvalues
from scatterbench.validation.numerics.reciprocity import reciprocity_error

angle = st.floats(0.0, math.radians(89.99))
azimuth = st.floats(-2 * math.pi, 2 * math.pi)
sigma = st.floats(1e-3, 3.0)
substrate = st.one_of(
    st.just(math.inf),
    st.builds(complex, st.floats(0.1, 5.0), st.floats(0.0, 9.0)),
)


@st.composite
def facet_models(draw):
    cls = draw(st.sampled_from([models.ExponentialSlopes, models.GaussianSlopes]))
    slopes = cls(sigma=draw(sigma), coverage=draw(st.floats(0.05, 1.0)))
    if draw(st.booleans()):
        slopes = models.AnisotropicExponentialSlopes(
            sigma_x=draw(sigma), sigma_y=draw(sigma), rotation=draw(st.floats(-3.2, 3.2))
        )
    coating = draw(st.sampled_from([1.0, draw(st.floats(1.0, 3.0))]))
    return models.SubsurfaceFacetBRDF(slopes=slopes, coating=coating, substrate=draw(substrate))


@settings(max_examples=150, deadline=None)
@given(facet_models(), angle, angle, azimuth)
def test_reciprocity_property(m, ti, tr, pr):
    r = reciprocity_error(m, np.array([ti]), np.array([tr]), np.array([pr]))
    assert r.scalar < 1e-9 and r.mueller < 1e-9
    if r.jones is not None:
        assert r.jones < 1e-9


@settings(max_examples=150, deadline=None)
@given(facet_models(), angle, angle, azimuth)
def test_m00_nonnegative_and_physical(m, ti, tr, pr):
    M = m.mueller(ti, tr, pr)
    assert np.all(np.isfinite(M))
    assert M[0, 0] >= 0
    ev = coherency_eigenvalues(M)
    assert ev[0] >= -1e-10 * M[0, 0] - 1e-300
    # non-depolarizing: a single Jones matrix, so the degree of polarization is 1
    if M[0, 0] > 1e-250:
        s = M @ np.array([1.0, 0.6, 0.8, 0.0])
        if s[0] > 1e-250:
            s = s / s[0]
            assert math.isclose(float(np.linalg.norm(s[1:])), 1.0, rel_tol=1e-6)
