"""Reciprocity: holds for the facet models and the check catches a model that breaks it."""

import math
from dataclasses import dataclass

import numpy as np

from scatterbench import models
from scatterbench.models.base import Model
from scatterbench.validation.checks.common import facet_suite
from scatterbench.validation.numerics.reciprocity import reciprocity_error


def test_facet_models_are_reciprocal(rng):
    ti, tr = rng.uniform(0, 1.5, (2, 500))
    pr = rng.uniform(-4, 4, 500)
    for m in facet_suite():
        r = reciprocity_error(m, ti, tr, pr)
        assert r.scalar < 1e-10 and r.mueller < 1e-10 and r.jones < 1e-10, (m, r)
        assert r.n > 0


@dataclass(frozen=True)
class Lopsided(Model):
    """Not reciprocal: weights the incidence direction more than the viewing direction."""

    def _mueller16(self, ti, tr, pr):
        base = models.FacetBRDF()._mueller16(ti, tr, pr)
        return base * (1.0 + 0.2 * np.cos(ti))

    def _jones_flat(self, ti, tr, pr):
        return models.FacetBRDF()._jones_flat(ti, tr, pr) * np.sqrt(1.0 + 0.2 * np.cos(ti))[:, None, None]


@dataclass(frozen=True)
class Swapped(Model):
    """Breaks only the polarized relation: exchanges the two cross-polarized Jones elements."""

    def _jones_flat(self, ti, tr, pr):
        J = models.FacetBRDF(substrate=1.5)._jones_flat(ti, tr, pr).copy()
        J[:, 0, 1], J[:, 1, 0] = J[:, 1, 0].copy(), -J[:, 0, 1].copy() * 1.5
        return J

    def _mueller16(self, ti, tr, pr):
        M = models.jones_to_mueller(self._jones_flat(ti, tr, pr))
        return M.reshape(-1, 16).T


def test_check_detects_violations(rng):
    ti, tr = rng.uniform(0.1, 1.3, (2, 200))
    pr = rng.uniform(-3, 3, 200)
    r = reciprocity_error(Lopsided(), ti, tr, pr)
    assert r.scalar > 1e-3
    r = reciprocity_error(Swapped(), ti, tr, pr)
    assert r.mueller > 1e-3 and r.jones > 1e-3


def test_anisotropic_sample_is_rotated_for_the_reversed_path():
    s = models.AnisotropicExponentialSlopes(0.05, 0.6, 0.4)
    m = models.SubsurfaceFacetBRDF(slopes=s, coating=1.5, substrate=1.37 + 7.62j)
    ti, tr, pr = np.array([0.3, 1.0]), np.array([0.9, 0.2]), np.array([1.0, -2.0])
    assert reciprocity_error(m, ti, tr, pr).mueller < 1e-10
    # evaluating the reversed path without the rotation would be wrong:
    naive = m.mueller(tr, ti, -pr)[:, 0, 0]
    assert np.max(np.abs(naive - m.mueller(ti, tr, pr)[:, 0, 0])) > 1e-3 * math.pi


@dataclass(frozen=True)
class _TurnsOneAngleAtATime(Model):
    """A user's anisotropic model whose ``rotated`` takes a single angle (``float(angle)``
    refuses an array): the reversed paths are then built geometry by geometry."""

    inner: Model = None
    depolarizing = False
    reciprocal = True

    def rotated(self, angle):
        return _TurnsOneAngleAtATime(inner=self.inner.rotated(float(angle)))

    def _mueller16(self, ti, tr, pr):
        return self.inner.flat_mueller16(ti, tr, pr)

    def _jones_flat(self, ti, tr, pr):
        return self.inner._jones_flat(ti, tr, pr)


def test_the_reversed_paths_of_a_model_set_equal_those_built_one_by_one():
    """An anisotropic model's reversed paths need the sample turned by pi - phi_r per geometry:
    one model set of the turns when ``rotated`` takes an array, else one model per geometry;
    both give the same bits (Mueller and Jones), and the set is what the shipped models take."""
    from scatterbench.models.base import rotated_set
    from scatterbench.validation.numerics.reciprocity import _reversed

    s = models.AnisotropicGGXSlopes(alpha_x=0.05, alpha_y=0.3, rotation=0.4)
    m = models.SubsurfaceFacetBRDF(slopes=s, coating=1.5, substrate=1.37 + 7.62j)
    one = _TurnsOneAngleAtATime(inner=m)
    assert rotated_set(m, np.zeros(3)) is not None and rotated_set(one, np.zeros(3)) is None
    rng = np.random.default_rng(4)
    ti, tr, pr = rng.uniform(0, 1.5, (3, 5)), rng.uniform(0, 1.5, (3, 5)), rng.uniform(-4, 4, (3, 5))
    for method in ("mueller", "jones"):
        assert np.array_equal(_reversed(m, ti, tr, pr, method), _reversed(one, ti, tr, pr, method))
    assert reciprocity_error(one, ti, tr, pr).mueller < 1e-10
