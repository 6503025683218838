"""Scene files: loading, validation errors naming file and key, mechanisms, evaluation."""

import csv
import math
import os
import re

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.validation.cli import main

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = references.scene_paths()


@pytest.mark.parametrize("path", SCENES, ids=os.path.basename)
def test_example_scenes_load_build_and_explain(path):
    sc = scene.load(path)
    mech = sc.mechanisms()
    assert mech and all(m.why for m in mech)
    model = sc.build()
    assert isinstance(model, models.Model)
    assert model.mueller(sc.theta_i, 0.3, 0.2).shape == (4, 4)


def test_coated_flakes_build_only_the_subsurface_facet_model():
    sc = scene.load(references.scene_path("aluminium_flakes_clearcoat.toml"))
    assert [type(m.model) for m in sc.mechanisms()] == [models.SubsurfaceFacetBRDF]
    m = sc.build()
    # the 0.7 deg detector averages the exponential distribution's cusp at the specular peak
    # by ~3% of the peak, more than the default tolerance: the aperture is kept (measured)
    assert isinstance(m, models.DetectorAperture) and math.isclose(m.aperture, math.radians(0.7))
    assert "kept" in sc.aperture_decision()
    m = m.model
    assert m.coating == 1.5 and m.substrate == 1.37 + 7.62j and m.slopes.sigma == 0.1
    # a point detector (the SCATMECH data's sidecar says aperture_deg = 0) builds the bare model
    assert sc.with_aperture(0.0).build() == m


BASE = 'name = "x"\n[illumination]\ntheta_i_deg = 30\n'


@pytest.mark.parametrize(
    "text, key",
    [
        ("name = 3\n[illumination]\ntheta_i_deg = 1\n", "name"),
        ('name = "x"\n', "[illumination]"),
        ('name = "x"\n[illumination]\ntheta_i_deg = 95\n', "theta_i_deg"),
        (BASE + 'polarization = "diagonal"\n', "polarization"),
        (BASE + 'source = "laser"\n', "source"),
        (BASE + 'source = "point"\n', "distance_mm"),
        (BASE + "[coating]\nindex = 0.9\n", "[coating] index"),
        (
            BASE + '[substrate]\nindex = [1.5, -0.1]\ndistribution = "gaussian"\nsigma = 0.1\n',
            "[substrate] index",
        ),
        (BASE + '[substrate]\nindex = 1.5\ndistribution = "gaussian"\n', "[substrate] sigma"),
        (
            BASE + '[substrate]\nindex = 1.5\ndistribution = "gaussian"\nsigma = -1\n',
            "[substrate] sigma: sigma",
        ),
        (BASE + '[substrate]\nindex = 1.5\ndistribution = "cauchy"\nsigma = 1\n', "distribution"),
        (BASE + "[substrat]\nindex = 1.5\n", "substrat"),
        (BASE + "[illumination.extra]\n", "extra"),
        ("name = [", "not valid TOML"),
    ],
)
def test_malformed_scene_names_file_and_key(text, key):
    with pytest.raises(ValueError) as exc:
        scene.loads(text, "sample.toml")
    msg = str(exc.value)
    assert msg.startswith("sample.toml") and key in msg


def test_flat_smooth_scene_has_no_mechanism():
    sc = scene.loads(BASE + "[coating]\nindex = 1.5\n[substrate]\nindex = [1.37, 7.62]\n", "flat.toml")
    assert sc.mechanisms() == []
    with pytest.raises(ValueError, match="no scattering mechanism"):
        sc.build()


def test_missing_file():
    with pytest.raises(ValueError, match="cannot read"):
        scene.load("/nonexistent/scene.toml")


def test_scene_command_writes_csv_and_png(tmp_path):
    path = references.scene_path("aluminium_flakes_clearcoat.toml")
    assert main(["scene", path, "--out", str(tmp_path)]) == 0
    rows = list(
        csv.reader(
            line for line in open(tmp_path / "aluminium_flakes_clearcoat.csv") if not line.startswith("#")
        )
    )
    assert rows[0] == ["scan", "theta_i_deg", "theta_r_deg", "phi_r_deg", "brdf", "eta_deg", "P", "P_C"]
    assert {r[0] for r in rows[1:]} == {"in-plane", "out-of-plane"}
    assert (tmp_path / "aluminium_flakes_clearcoat.png").stat().st_size > 1000
    assert main(["scene", "/nonexistent.toml", "--out", str(tmp_path)]) == 2


def test_with_values_rebuilds_and_revalidates():
    sc = scene.load(references.scene_paths()[0]).with_aperture(0.0)
    s2 = sc.with_values({"substrate.sigma": 0.25, "substrate.index[1]": 7.0, "coating.index": 1.6})
    m = s2.build()
    assert m.slopes.sigma == 0.25 and m.substrate == 1.37 + 7.0j and m.coating == 1.6
    assert sc.build().slopes.sigma == 0.1  # the original is untouched
    assert s2.get_value("substrate.index[0]") == 1.37
    with pytest.raises(ValueError, match=r"\[substrate\].*sigma"):
        sc.with_values({"substrate.sigma": -1.0})
    with pytest.raises(ValueError, match="not set"):
        sc.with_values({"substrate.nothing": 1.0})


def _ct_scene(extra_illum="", extra_sub=""):
    return (
        'name = "plate"\n[illumination]\ntheta_i_deg = 45\n' + extra_illum + "[coating]\nindex = 1.5\n"
        '[substrate]\nindex = [2.29, 3.37]\nmodel = "cook-torrance"\n' + extra_sub
    )


def test_cook_torrance_scenes_and_point_source_decision():
    near = scene.loads(
        _ct_scene('source = "point"\ndistance_mm = 100\nsample_radius_mm = 10\n', "m = 0.03\n"), "p.toml"
    )
    m = near.build()
    assert isinstance(m, models.PointSourceBRDF) and isinstance(m.model, models.VarnishedCookTorranceBRDF)
    assert "kept" in near.source_decision()
    far = scene.loads(
        _ct_scene('source = "point"\ndistance_mm = 1e7\nsample_radius_mm = 1\n', "m = 0.03\n"), "f.toml"
    )
    assert isinstance(far.build(), models.VarnishedCookTorranceBRDF)
    assert "collimated" in far.source_decision()
    brushed = scene.loads(
        _ct_scene("", "m_parallel = 0.03\nm_perpendicular = 0.3\nstroke_angle_deg = 30\n"), "b.toml"
    )
    b = brushed.build()
    assert b.slopes.m_perpendicular == 0.3 and abs(b.slopes.stroke_angle - math.radians(30)) < 1e-15


@pytest.mark.parametrize(
    "extra_sub, key",
    [
        ("", "m_parallel"),
        ("m = 0.1\nm_parallel = 0.2\n", "[substrate] m"),
        ('m = 0.1\nnormalization = "unit"\n', "normalization"),
        ("m = -1\n", "[substrate] m"),
    ],
)
def test_cook_torrance_scene_errors(extra_sub, key):
    with pytest.raises(ValueError) as exc:
        scene.loads(_ct_scene("", extra_sub), "ct.toml")
    assert key in str(exc.value) and str(exc.value).startswith("ct.toml")


def _scene(name):
    return scene.load(references.scene_path(name))


def test_volume_scenes_build_only_what_they_declare():
    white = _scene("glossy_white_paint.toml")
    assert [type(m.model) for m in white.mechanisms()] == [models.DiffuseSubsurfaceBRDF]
    red = _scene("red_pigmented_paint.toml")
    assert [type(m.model) for m in red.mechanisms()] == [
        models.FacetBRDF,
        models.SingleScatterBRDF,
        models.DiffuseSubsurfaceBRDF,
    ]
    carc = _scene("green_carc.toml")
    assert [type(m.model) for m in carc.mechanisms()] == [models.RoughDiffuseBRDF]
    mc = carc.build()
    assert mc.surface and mc.pairs == 5000 and mc.slopes.sigma == 2.0 and mc.rho == 0.05 and mc.phase.g == 0.3


def test_preset_scenes_are_the_paper_models():
    """The scene files of seed 003's presets hold the models (and parameters) of the paper's
    Fig. 2-3 as the preset builder wrote them before the presets became data."""
    white = _scene("glossy_white_paint.toml").build()
    assert white == models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.93)
    phase = models.HenyeyGreenstein(g=0.3, polarized=True)
    red = _scene("red_pigmented_paint.toml").build()
    assert red == (
        1.0 * models.FacetBRDF(slopes=models.GaussianSlopes(sigma=0.05), substrate=1.5)
        + 1.0 * models.SingleScatterBRDF(coating=1.5, phase=phase)
        + 1.0 * models.DiffuseSubsurfaceBRDF(coating=1.5, rho=0.1)
    )
    carc = _scene("green_carc.toml").build()
    assert carc == models.RoughDiffuseBRDF(
        slopes=models.ExponentialSlopes(sigma=2.0),
        coating=1.5,
        phase=phase,
        rho=0.05,
        pairs=5000,
        seed=0,
        surface=True,
    )


def test_smooth_scenes_never_call_the_monte_carlo(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("Monte Carlo called")

    monkeypatch.setattr(models.RoughDiffuseBRDF, "_estimate", boom)
    for path in references.scene_paths():
        sc = scene.load(path)
        if any(isinstance(m.model, models.RoughDiffuseBRDF) for m in sc.mechanisms()):
            continue
        sc.build().mueller(sc.theta_i, np.linspace(0, 1.4, 5), 0.4)
    with pytest.raises(AssertionError, match="Monte Carlo called"):
        _scene("green_carc.toml").build().mueller(1.0, 0.5, 0.0)


@pytest.mark.parametrize(
    "text, key",
    [
        (BASE + "[volume]\nrho = 0.5\n", "[coating]"),
        (BASE + "[coating]\nindex = 1.5\n[volume]\nrho = 1.5\n", "[volume] rho"),
        (BASE + "[coating]\nindex = 1.5\n[volume]\nrho = 0.5\npairs = 1\n", "[volume] pairs"),
        (BASE + '[coating]\nindex = 1.5\n[volume]\nrho = 0.5\ninterface = "wavy"\n', "[volume] interface"),
        (BASE + "[coating]\nindex = 1.5\n[volume]\nrho = 0\nsingle = false\n", "no scattering"),
        (BASE + "[coating]\nindex = 1.5\n[volume]\ncolour = 1\n", "colour"),
    ],
)
def test_volume_errors(text, key):
    with pytest.raises(ValueError) as exc:
        scene.loads(text, "v.toml")
    assert key in str(exc.value) and str(exc.value).startswith("v.toml")


_MB = (
    BASE + '[substrate]\nmodel = "maxwell-beard"\nindex = 1.5\ndistribution = "gaussian"\nsigma = 0.1\n'
    "rho_d = 0.02\nrho_v = 0.01\n"
)


def test_maxwell_beard_scene_builds_the_model_with_degrees_converted():
    sc = scene.loads(_MB + "tau_deg = 14.0\nomega_deg = 40.0\npolarized = false\n", "mb.toml")
    (mech,) = sc.mechanisms()
    m = sc.build()
    assert isinstance(m, models.MaxwellBeardBRDF) and "Maxwell-Beard" in mech.why
    assert m.rho_d == 0.02 and m.rho_v == 0.01 and m.slopes.sigma == 0.1 and not m.polarized
    assert math.isclose(m.tau, math.radians(14.0)) and math.isclose(m.omega, math.radians(40.0))
    # defaults are the model's own (tau 0.25 rad, Omega 0.7 rad, polarized specular term)
    d = scene.loads(_MB, "mb.toml").build()
    ref = models.MaxwellBeardBRDF(slopes=models.GaussianSlopes(0.1), substrate=1.5, rho_d=0.02, rho_v=0.01)
    assert d == ref.replace(polarized=True)
    # fits change its parameters through the dotted keys
    assert sc.with_values({"substrate.rho_v": 0.05}).build().rho_v == 0.05


@pytest.mark.parametrize(
    "text, key",
    [
        (_MB.replace("rho_d = 0.02", "rho_d = -0.1"), "rho_d"),
        (_MB.replace('distribution = "gaussian"\nsigma = 0.1\n', ""), "distribution"),
        (_MB + "tau_deg = 0\n", "tau_deg"),
        (_MB + 'polarized = "yes"\n', "polarized"),
        (_MB + "[coating]\nindex = 1.5\n", "[coating]"),
        (
            BASE + "[substrate]\nindex = 1.5\nrho_d = 0.1\n",
            "rho_d",
        ),  # a Maxwell-Beard key on a facet substrate
        (BASE + '[substrate]\nindex = 1.5\nmodel = "lambert"\n', "model"),
    ],
)
def test_maxwell_beard_scene_errors(text, key):
    with pytest.raises(ValueError) as exc:
        scene.loads(text, "mb.toml")
    assert key in str(exc.value) and str(exc.value).startswith("mb.toml")


def test_detector_aperture_is_neglected_where_it_changes_nothing():
    white = _scene("glossy_white_paint.toml")  # totally diffuse: smooth on the scale of 0.7 deg
    ap = white.with_aperture(0.7)
    assert ap.build() == white.build() and "neglected" in ap.aperture_decision()
    assert "detector aperture 0.7 deg" in ap.describe()
    # a 5 deg cone near grazing, where the interface's transmission falls, is not negligible
    assert isinstance(white.with_aperture(5.0).build(), models.DetectorAperture)


def test_decisions_are_measured_once_and_can_be_imposed():
    iron = _scene("brushed_varnished_iron_point_source.toml")
    d = iron.decisions()
    assert d == {"point_source": True, "aperture_resolution": None}
    assert isinstance(iron.build(decisions=d), models.PointSourceBRDF)
    forced = iron.build(decisions={"point_source": False, "aperture_resolution": None})
    assert isinstance(forced, models.VarnishedCookTorranceBRDF)
    flakes = _scene("aluminium_flakes_clearcoat.toml")
    assert flakes.decisions() == {"point_source": False, "aperture_resolution": 8}
    m = flakes.build(decisions={"point_source": False, "aperture_resolution": 2})
    assert isinstance(m, models.DetectorAperture) and m.resolution == 2
    assert flakes.build(decisions={"point_source": False, "aperture_resolution": None}) == m.model


# ----------------------------------------------------------------------- scenes derived from the models
def test_values_are_validated_by_the_models_declared_parameters():
    """The scene wraps the model's own error with the file and the key; no range of its own
    (e.g. [volume] g is HenyeyGreenstein's open interval (-1, 1))."""
    vol = BASE + "[coating]\nindex = 1.5\n[volume]\nrho = 0.5\n"
    sc = scene.loads(vol + "g = 0.9999995\n", "v.toml")
    assert sc.volume["g"] == 0.9999995 and sc.build().terms[0][1].phase.g == 0.9999995
    for text, message in (
        (vol + "g = 1.0\n", "v.toml: [volume] g: g must be a finite real number in (-1, 1); got 1.0"),
        (
            vol + "seed = -2\n",
            "v.toml: [volume] seed: seed must be an integer in [0, inf) or a numpy.random.Generator; got -2",
        ),
        (vol + "polarized = 1\n", "v.toml: [volume] polarized: polarized must be one of True, False; got 1"),
        (_MB + "tau_deg = -3\n", "v.toml: [substrate] tau_deg: tau must be a finite real number in (0, inf)"),
    ):
        with pytest.raises(scene.SceneError) as exc:
            scene.loads(text, "v.toml")
        assert str(exc.value).startswith(message), str(exc.value)
    with pytest.raises(scene.SceneError, match=r"tau_deg = -3 deg in the file, converted to radians"):
        scene.loads(_MB + "tau_deg = -3\n", "v.toml")


@pytest.mark.parametrize(
    "extra_sub, convention",
    [
        ("m = 0.03\n", "corrected"),  # the scene's default: energy normalization, refracted solid angle
        ('m = 0.03\nconvention = "paper"\n', "paper"),
        ('m = 0.03\nnormalization = "energy"\n', "corrected"),  # with the default solid angle
        ('m = 0.03\nnormalization = "published"\nsolid_angle = "published"\n', "paper"),
    ],
)
def test_cook_torrance_scene_convention(extra_sub, convention):
    m = scene.loads(_ct_scene("", extra_sub), "c.toml").build()
    assert isinstance(m, models.VarnishedCookTorranceBRDF) and m.convention == convention


@pytest.mark.parametrize(
    "extra_sub, message",
    [
        (
            'm = 0.03\nnormalization = "published"\n',
            "[substrate] normalization: normalization='published' with",
        ),
        ('m = 0.03\nconvention = "energy"\n', "[substrate] convention: convention must be one of"),
        (
            'm = 0.03\nconvention = "paper"\nsolid_angle = "published"\n',
            "[substrate] solid_angle: solid_angle: old",
        ),
    ],
)
def test_cook_torrance_scene_convention_errors(extra_sub, message):
    with pytest.raises(scene.SceneError) as exc:
        scene.loads(_ct_scene("", extra_sub), "c.toml")
    assert str(exc.value).startswith("c.toml: " + message), str(exc.value)


def test_one_assembly_measures_once(monkeypatch):
    from scatterbench.models.scene import decisions

    calls = []
    real = decisions._deviation
    monkeypatch.setattr(decisions, "_deviation", lambda *a: calls.append(1) or real(*a))
    flakes = _scene("aluminium_flakes_clearcoat.toml")
    a = flakes.assemble()
    measured = len(calls)
    assert measured > 1 and isinstance(a, scene.Assembly)
    assert a.decisions == {"point_source": False, "aperture_resolution": 8} and "kept" in a.aperture_reason
    text = flakes.describe()
    assert flakes.build() is a.model and flakes.decisions() == a.decisions
    assert flakes.source_decision() == a.source_reason and a.aperture_reason in text
    assert len(calls) == measured  # describe, build, decisions and the reasons reuse it
    assert [m.name for m in a.mechanisms] == [m.name for m in flakes.mechanisms()]
    flakes.assemble(tol=1e-2)
    assert len(calls) > measured  # another tolerance is another measurement


def test_distributions_table_keeps_its_form():
    cls, keys = scene.DISTRIBUTIONS["anisotropic-gaussian"]
    assert cls is models.AnisotropicGaussianSlopes and keys == (
        "sigma_x",
        "sigma_y",
        "rotation_deg",
        "coverage",
    )
    assert set(scene.DISTRIBUTIONS) == {
        "exponential",
        "gaussian",
        "anisotropic-exponential",
        "anisotropic-gaussian",
        "gaussian-angle",
        "exponential-angle",
        "ggx",
        "anisotropic-ggx",
    }


@pytest.mark.parametrize("rough", [True, False], ids=["rough-top", "smooth-top"])
@pytest.mark.parametrize("interface", ["rough", "smooth"])
def test_monte_carlo_volume_is_one_rule(rough, interface):
    """The volume is the Monte Carlo model exactly where a [coating.roughness] meets
    ``interface = 'rough'`` (models.scene.assembly.monte_carlo_volume): the assembly builds
    RoughDiffuseBRDF there and only there, ``pairs`` is accepted there and only there, and
    [coating.film] is refused there and only there."""
    want = rough and interface == "rough"
    text = (
        BASE.replace("theta_i_deg = 30\n", "theta_i_deg = 30\nwavelength_nm = 550.0\n")
        + "[coating]\nindex = 1.5\n"
        + ("[coating.roughness]\ndistribution = 'gaussian'\nsigma = 0.3\n" if rough else "")
        + f"[volume]\nrho = 0.5\ninterface = '{interface}'\n"
    )
    kinds = [type(m.model) for m in scene.loads(text, "v.toml").mechanisms()]
    assert (models.RoughDiffuseBRDF in kinds) is want
    film = "[coating.film]\nlayers = [{index = 1.2247, thickness_nm = 112.3}]\n"
    for extra, key in (("pairs = 100\n", "[volume] pairs"), (film, "[coating.film]")):
        refused = key == "[volume] pairs" and not want or key == "[coating.film]" and want
        if refused:
            with pytest.raises(scene.SceneError, match=re.escape(f"v.toml: {key}")):
                scene.loads(text + extra, "v.toml")
        else:
            assert scene.loads(text + extra, "v.toml").mechanisms()


_ROUGH = (
    BASE
    + "[coating]\nindex = 1.4\n[coating.roughness]\ndistribution = 'gaussian'\nsigma = 0.3\n"
    + "[volume]\nrho = 0.9\nsingle = false\ninterface = 'rough'\n"
)


def test_quadrature_volume_is_the_facet_term_plus_the_expected_diffuser():
    """``[volume] method = 'quadrature'``: the rough surface's facet reflection and
    RoughSubsurfaceBRDF, the Monte Carlo's direct reflection and totally diffuse term without
    its statistical error (within 4 standard errors of it at 2e5 pairs)."""
    sc = scene.loads(_ROUGH + "method = 'quadrature'\n", "q.toml")
    assert [type(m.model) for m in sc.mechanisms()] == [models.FacetBRDF, models.RoughSubsurfaceBRDF]
    mc = scene.loads(_ROUGH + "pairs = 200000\n", "m.toml").build()
    ti, tr, pr = np.array([0.2, 0.9]), np.array([0.6, 1.1]), np.array([0.4, 2.0])
    M, err = mc.mueller_with_error(ti, tr, pr)
    Q = sc.build().mueller(ti, tr, pr)
    live = err > 0
    assert np.max(np.abs(M - Q)[live] / err[live]) < 4.0


@pytest.mark.parametrize(
    "extra, key",
    [
        ("method = 'exact'\n", "[volume] method"),
        ("method = 'quadrature'\npairs = 100\n", "[volume] pairs"),
        ("method = 'quadrature'\nseed = 1\n", "[volume] seed"),
    ],
)
def test_quadrature_volume_errors(extra, key):
    with pytest.raises(scene.SceneError, match=re.escape(f"v.toml: {key}")):
        scene.loads(_ROUGH + extra, "v.toml")


@pytest.mark.parametrize(
    "text, why",
    [
        (_ROUGH.replace("single = false", "single = true") + "method = 'quadrature'\n", "single = false"),
        (_ROUGH.replace("'gaussian'", "'exponential'") + "method = 'quadrature'\n", "Gaussian"),
        (_ROUGH.replace("interface = 'rough'", "interface = 'smooth'") + "method = 'quadrature'\n", "rough"),
    ],
)
def test_quadrature_volume_refuses_what_it_does_not_compute(text, why):
    with pytest.raises(scene.SceneError, match=r"v\.toml: \[volume\] method") as exc:
        scene.loads(text, "v.toml")
    assert why in str(exc.value)
