"""How model sets are evaluated: derived per-element quantities computed once per distinct
element, and the same kernel route (float64 and float32) as single models."""

import numpy as np

import models
from models import smooth_interface


def test_diffuse_subsurface_set_runs_one_quadrature_per_distinct_coating(monkeypatch):
    """R-bar is a scipy quadrature: a set of 64 coatings evaluated in several chunks runs
    it 64 times (it ran twice per coating: once deciding on the kernel, once per chunk)."""
    calls = []
    quad = smooth_interface.integrate.quad
    monkeypatch.setattr(smooth_interface.integrate, "quad", lambda *a, **k: calls.append(1) or quad(*a, **k))
    smooth_interface._rbar.cache_clear()
    coating = np.linspace(1.1, 1.9, 64).reshape(64, 1)
    m = models.DiffuseSubsurfaceBRDF(coating=coating, rho=0.9)
    ti = np.linspace(0.0, 1.4, 2000)  # 128000 geometries: two kernel chunks
    M = m.mueller(ti, 0.3, 0.0)
    assert len(calls) == 64
    for w in (0, 37, 63):
        one = models.DiffuseSubsurfaceBRDF(coating=float(coating[w, 0]), rho=0.9)
        assert one.rbar == m.rbar[w, 0]
        assert np.array_equal(one.mueller(ti, 0.3, 0.0), M[w])
    assert len(calls) == 64
