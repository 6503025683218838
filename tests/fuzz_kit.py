"""Helpers of the fuzz tests (test_fuzz_loaders, test_scene_slopes_shadowing_films): mostly
well-formed inputs, and a check that a fuzz ran both its success branch and its refusals."""

from __future__ import annotations

import collections

from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def mostly(good, bad, one_in):
    """``good``, or ``bad`` once in ``one_in`` draws."""
    return st.integers(0, one_in - 1).flatmap(lambda k: bad if k == 0 else good)


def both_outcomes(strategy, outcome, at_least):
    """Run ``outcome`` on FUZZ's examples of ``strategy`` (a tuple is passed as arguments) and
    check that each of its results, ``"built"`` and ``"refused"``, came ``at_least`` times:
    the fuzz reached the success branch, not only the refusals."""
    seen = collections.Counter()

    @FUZZ
    @given(strategy)
    def fuzz(example):
        result = outcome(*example) if isinstance(example, tuple) else outcome(example)
        event(result)
        seen[result] += 1

    fuzz()
    assert seen["built"] >= at_least and seen["refused"] >= at_least, dict(seen)
