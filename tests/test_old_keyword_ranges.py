"""Old keywords that set a declared parameter are checked in that parameter's range and
named as the user typed them."""

import re

import pytest

from scatterbench import models
from scatterbench.models.params import SLOPE_WIDTH_MAX, SLOPE_WIDTH_MIN

RANGE = "^" + re.escape(f"m must be a finite real number in [{SLOPE_WIDTH_MIN:g}, {SLOPE_WIDTH_MAX:g}]; got ")


@pytest.mark.parametrize("cls", [models.CookTorranceBRDF, models.VarnishedCookTorranceBRDF])
@pytest.mark.parametrize("m", [-1.0, 0.0, 1e-9, 1e9, float("nan"), True])
def test_old_m_is_checked_in_the_slope_width_range_and_named_m(cls, m):
    with pytest.raises(ValueError, match=RANGE):
        cls(m=m)
    with pytest.raises(ValueError, match=RANGE):
        cls().replace(m=m)


@pytest.mark.parametrize("cls", [models.CookTorranceBRDF, models.VarnishedCookTorranceBRDF])
def test_old_m_at_the_range_ends_is_accepted(cls):
    for m in (SLOPE_WIDTH_MIN, SLOPE_WIDTH_MAX):
        s = cls(m=m).slopes
        assert (s.sigma if isinstance(s, models.GaussianSlopes) else s.m_perpendicular) == m
