"""A layer stack (models.FilmStack) where a facet model's substrate index goes is a declared
value like any other: the parameter check accepts it, the model-set machinery walks into it,
and a scene binding and a fit with a free film thickness work (they crashed on it once)."""

import dataclasses
import math

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import modelset, scene
from scatterbench.models.scene import binding
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.recovery import subsample

PEARL = references.scene_path("pearlescent_mica_tio2.toml")
THICKNESS = "substrate.film.layers[0].thickness_nm"
STACK = models.FilmStack(layers=((2.6, 130.0),), substrate=1.58, wavelength_nm=550.0)


@pytest.mark.parametrize("cls", [models.FacetBRDF, models.SubsurfaceFacetBRDF])
def test_the_declared_substrate_takes_a_stack_and_still_checks_indices(cls):
    assert cls.check_parameter("substrate", STACK) is STACK
    assert cls(slopes=models.GaussianSlopes(0.1), substrate=STACK).substrate is STACK
    assert cls.check_parameter("substrate", 1.5) == 1.5 + 0j
    with pytest.raises(ValueError, match=r"^substrate must be n \+ ik .* got \(1-1j\)"):
        cls.check_parameter("substrate", 1 - 1j)
    with pytest.raises(ValueError, match=r"^substrate must be n \+ ik"):
        cls(substrate="glass")


def test_model_set_leaves_walk_into_the_stack():
    m = scene.load(PEARL).build()
    leaves = modelset.scalar_leaves(m)
    assert leaves[("substrate", "wavelength_nm")] == (550.0, "real")
    assert ("substrate",) not in leaves
    # a model set over the stack's wavelength is one model per element
    ms = m.with_values({"substrate.wavelength_nm": np.array([[500.0], [600.0]])})
    assert ms.param_shape == (2, 1)
    tr = np.array([0.4, 0.5, 0.6])
    M = ms.mueller(0.5, tr, 0.0)
    for i, w in enumerate((500.0, 600.0)):
        assert np.array_equal(M[i], m.with_values({"substrate.wavelength_nm": w}).mueller(0.5, tr, 0.0))


def test_a_free_film_thickness_binds_and_its_likelihood_evaluates():
    sc = scene.load(PEARL)
    m = sc.with_values({THICKNESS: 140.0}).build()
    assert m.substrate.layers[0][1] == 140.0
    # the thickness is no model-set leaf: no binding, the fit rebuilds the scene per walker
    assert binding.bind(sc, {THICKNESS: (100.0, 160.0)}) is None
    assert binding.bind(sc, {"substrate.sigma": (0.1, 0.2)}) is not None
    data = subsample(load_data(references.data_path("scatmech_flake_measurement.csv")), 20)
    # the committed data are at 632.8 nm, the scene at 550 nm (a mismatch Likelihood refuses):
    # the data relabelled at the scene's wavelength, as measurements taken there
    data = dataclasses.replace(data, meta={**data.meta, "wavelength_nm": sc.wavelength_nm})
    spec = fitspec_from(sc, [f"{THICKNESS}:100:160", "substrate.sigma:0.1:0.2"], ["brdf=0.05"])
    lik = Likelihood(sc, spec, data)
    U = np.array([[130.0, 0.15], [140.0, 0.12], [170.0, 0.15]])
    L = lik.batch(U)
    assert np.all(np.isfinite(L[:2])) and L[2] == -math.inf  # the last one is out of bounds
    assert np.array_equal(L[:2], [lik.loglike_rebuilt(u) for u in U[:2]])
    assert L[0] != L[1]
