"""Each model class carries its own facts (models.facts): its correspondence, its SCATMECH
equivalent, its stability-sweep instances, the kit's variant, and a slope distribution's
kernel code."""

import math
import sys

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import kernel_specs
from scatterbench.models import slopes as S
from scatterbench.models.facts import Correspondence, scatmech_index
from scatterbench.models.stroke_slopes import StrokeSlopes
from scatterbench.validation.checks import seed003
from scatterbench.validation.checks.conformance_scatmech import committed_cases, normalized
from scatterbench.validation.checks.seed000 import scatmech_facet_model
from scatterbench.validation.testing import check_model, shipped_models

MODELS = list(models.Model.registry)


@pytest.mark.parametrize("cls", MODELS, ids=lambda c: c.__name__)
def test_every_model_class_declares_its_correspondence(cls):
    c = cls.correspondence
    assert isinstance(c, Correspondence) and c.paper and c.scatmech and c.mitsuba
    assert "correspondence" in vars(cls), f"{cls.__name__} inherits another class's correspondence"


def test_a_class_with_a_scatmech_equivalent_says_so_in_its_correspondence():
    for cls in MODELS:
        has_hook = isinstance(vars(cls).get("scatmech"), property)
        assert has_hook == (cls.correspondence.scatmech != "—"), cls.__name__


def _slope_classes():
    found = [StrokeSlopes] + [
        c
        for c in vars(S).values()
        if isinstance(c, type) and issubclass(c, S.SlopeDistribution) and not c.__name__.startswith("_")
    ]
    return [c for c in found if c is not S.SlopeDistribution]


@pytest.mark.parametrize("cls", _slope_classes(), ids=lambda c: c.__name__)
def test_every_slope_class_has_a_kernel_code_or_says_it_has_none(cls):
    """``kernel_code`` is one of the kernels' codes (each family its own) with a 4-row
    ``kernel_row``, or ``None``: tabulated slopes and the angle distributions, whose
    normalizations are quadratures, run on the numpy path."""
    code = cls.kernel_code
    if code is None:
        assert cls in (S.TabulatedSlopes, S.GaussianAngles, S.ExponentialAngles)
        assert kernel_specs.slope_rows(cls()) is None
        return
    assert code in kernel_specs.SLOPE_CODES
    others = [c for c in _slope_classes() if c is not cls and c.kernel_code == code]
    assert not others, f"{cls.__name__} shares code {code} with {others}"
    kind, row = kernel_specs.slope_rows(cls())
    assert kind == code and len(row) == 4 and row[3] == cls().coverage


def test_the_kernels_know_every_code_a_class_names():
    codes = {c.kernel_code for c in _slope_classes()} - {None}
    assert codes == set(kernel_specs.SLOPE_CODES)


# ----------------------------------------------------------------------------- SCATMECH hooks
def _seed003_model(kind, ref, i):
    """The model the registry's check_scatmech_seed003 compares with committed case ``i``."""
    return seed003._model_for(kind, ref, i)


def _committed_models():
    """``(model, normalized committed parameters)`` for every committed SCATMECH case."""
    cases = committed_cases()
    out, k = [], 0
    ref = references.scatmech_facet()
    for i in range(len(ref["model"])):
        out.append((scatmech_facet_model(ref, i)[0], cases[k][:2]))
        k += 1
    for kind in ("diffuse", "single", "btdf", "mb"):
        ref = references.scatmech_seed003(kind)
        for i in range(len(ref["theta_i"])):
            out.append((_seed003_model(kind, ref, i), cases[k][:2]))
            k += 1
    assert k == len(cases)
    return out


def test_each_model_names_the_scatmech_parameters_of_the_committed_cases():
    """The models the registry's SCATMECH checks build from each committed case name, through
    their own ``scatmech`` hook, exactly the SCATMECH model and parameters that made the case."""
    pairs = _committed_models()
    assert len(pairs) > 1000
    for model, (name, params) in pairs:
        assert model.scatmech is not None, model
        assert normalized(*model.scatmech) == (name, params), model


@pytest.mark.parametrize(
    "model",
    [
        models.FacetBRDF(shadowing="smith"),
        models.FacetBRDF(slopes=models.GGXSlopes(0.1)),
        models.FacetBRDF(slopes=models.ExponentialSlopes(0.1, coverage=0.5)),
        models.FacetBRDF(substrate=math.inf),
        models.FacetBRDF(substrate=models.FilmStack(layers=((2.0, 100.0),), substrate=1.5)),
        models.FacetBRDF(slopes=models.GaussianSlopes(np.array([0.1, 0.2]))),
        models.SubsurfaceFacetBRDF(coating_films=models.Films(layers=((2.0, 100.0),))),
        models.FacetBTDF(convention="corrected"),
        models.SingleScatterBRDF(),  # polarized Rayleigh-Gans phase: none in current SCATMECH
        models.MaxwellBeardBRDF(),  # the published scalar form
        models.MaxwellBeardBRDF(polarized=True, rho_d=0.1),  # a Lambertian term besides
        models.DiffuseSubsurfaceBRDF(rho=np.array([0.5, 0.9])),
        models.CookTorranceBRDF(),
    ],
    ids=repr,
)
def test_no_scatmech_equivalent_of_these_options(model):
    assert model.scatmech is None


def test_scatmech_index_strings():
    assert scatmech_index(1.37 + 7.62j) == "(1.37,7.62)" and scatmech_index(1.5) == "(1.5,0.0)"
    assert scatmech_index(math.inf) is None and scatmech_index(np.array([1.5])) is None


_COMPARED = ("FacetBRDF", "SubsurfaceFacetBRDF", "FacetBTDF", "DiffuseSubsurfaceBRDF")


def test_the_kit_compares_the_shipped_scatmech_models_with_committed_values(monkeypatch):
    """Without pySCATMECH (as in CI) the kit's ``scatmech`` check runs, not skips, on the shipped
    facet models and the diffuse subsurface model, against the committed reference values."""
    monkeypatch.setitem(sys.modules, "pySCATMECH", None)
    monkeypatch.setitem(sys.modules, "pySCATMECH.brdf", None)
    shipped = dict(shipped_models())
    for label in _COMPARED:
        r = check_model(shipped[label], checks=["scatmech"]).results[0]
        assert r.status == "pass" and "committed SCATMECH reference values" in r.detail, (label, r.message)
    skipped = {label for label, m in shipped.items() if m.scatmech is None}
    assert skipped == set(shipped) - set(_COMPARED)


# ----------------------------------------------------------------------------- sweep and kit
@pytest.mark.parametrize("cls", MODELS, ids=lambda c: c.__name__)
def test_sweep_instances_and_kit_variant_are_the_class_s_own(cls):
    base = cls.sweep_base()
    if cls is models.Sum:
        assert base is None  # no defaults: its terms are the other models
        return
    assert type(base) is cls
    names = {p.name for p in cls.parameters()}
    for extra, swept in cls.sweep_extras():
        assert type(extra) is cls and set(swept) <= names
    assert set(cls.kit_variant) <= names
    assert type(base.replace(**cls.kit_variant)) is cls
