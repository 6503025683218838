"""Property-based fuzz of the three loaders of user files: whatever the input, the scene
loader raises only ``SceneError``, the data loader only ``DataFileError`` and the fit-spec
parser only ``FitSpecError`` (or ``SceneError`` for the scene it reads); anything else
escaping is a bug the command line would report as an internal error (exit 3)."""

from __future__ import annotations

import json
import math
import os
import tempfile

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from models import scene
from models.scene import SceneError
from validation.fitting.datafile import COLUMNS, DataFileError, Dataset, load_data
from validation.fitting.fitspec import FitSpec, FitSpecError, fitspec_from, parse_exclude, parse_free

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ----------------------------------------------------------------------------- values a file may hold
_scalars = st.one_of(
    st.booleans(),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.sampled_from(
        ["inf", "gaussian", "exponential", "cook-torrance", "maxwell-beard", "point", "linear:45"]
        + ["ggx", "anisotropic-ggx", "smith", "smith-correlated", "none", "blinn"]
    ),
)
_values = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)
_SCENE_KEYS = {
    "illumination": [
        "theta_i_deg",
        "polarization",
        "wavelength_nm",
        "source",
        "distance_mm",
        "sample_radius_mm",
    ],
    "substrate": [
        "index",
        "distribution",
        "model",
        "sigma",
        "sigma_x",
        "sigma_y",
        "rotation_deg",
        "m",
        "rho_d",
        "alpha",
        "alpha_x",
        "shadowing",
        "film",
    ],
    "coating": ["index", "roughness"],
    "volume": ["rho", "g", "polarized", "pairs", "seed", "single", "single_weight", "interface"],
    "detector": ["aperture_deg"],
    "fit": ["free", "noise", "mask"],
}


@st.composite
def scene_dicts(draw):
    """Dicts shaped like a scene (its tables and keys), with any values, some keys missing."""
    out = {"name": draw(st.one_of(st.just("fuzz"), _scalars))}
    for table, keys in _SCENE_KEYS.items():
        if draw(st.booleans()):
            chosen = draw(st.lists(st.sampled_from(keys), unique=True, max_size=len(keys)))
            out[table] = {k: draw(_values) for k in chosen} if draw(st.integers(0, 9)) else draw(_values)
    return out


def _scene_raises_only_scene_errors(call):
    try:
        sc = call()
    except SceneError:
        return None
    assert isinstance(sc, scene.Scene)
    return sc


@FUZZ
@given(scene_dicts())
def test_scene_dicts_raise_only_scene_errors(data):
    sc = _scene_raises_only_scene_errors(lambda: scene.from_dict(data, "fuzz.toml"))
    if sc is not None:  # a valid scene also describes itself or says why it cannot be built
        try:
            sc.mechanisms()
        except SceneError:
            pass


@FUZZ
@given(st.text(max_size=300))
def test_scene_text_raises_only_scene_errors(text):
    _scene_raises_only_scene_errors(lambda: scene.loads(text, "fuzz.toml"))


_TOML_PIECES = st.sampled_from(
    [
        'name = "x"\n',
        "[illumination]\n",
        "theta_i_deg = 45\n",
        "[substrate]\n",
        "index = [1.5, 0.1]\n",
        'distribution = "gaussian"\n',
        "sigma = 0.1\n",
        "[coating]\n",
        "index = 1.5\n",
        "[volume]\n",
        "rho = 0.5\n",
        "[",
        "]",
        "{",
        "= ",
        "1e999",
        "nan",
        '"',
        "\x00",
        "\ufeff",
        "9" * 30,
        "[[fit.free]]\n",
        "a.b.c = 1\n",
    ]
)


@FUZZ
@given(st.lists(_TOML_PIECES, max_size=25), st.binary(max_size=8))
def test_scene_files_raise_only_scene_errors(pieces, tail):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "fuzz.toml")
        with open(path, "wb") as fh:
            fh.write("".join(pieces).encode("utf-8") + tail)
        _scene_raises_only_scene_errors(lambda: scene.load(path))


# ----------------------------------------------------------------------------- data files
_CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(
        ["", "s", "p", "unpolarized", "linear:45", "linear:nan", "1e400", "-0", "0x1", "1_0", '"', "\x00"]
    ),
    st.text(max_size=6),
)
_COLUMN_NAMES = st.sampled_from([*COLUMNS, "incident", "theta_i", "colour", ""])
_SIDECARS = st.one_of(
    st.none(),
    st.dictionaries(
        st.sampled_from(
            ["format", "wavelength_nm", "aperture_deg", "incident_polarization", "truth", "sample", "x"]
        ),
        _values,
        max_size=4,
    ).map(lambda d: json.dumps(d, allow_nan=True, default=str)),
    st.text(max_size=40),
)


@FUZZ
@given(
    st.lists(_COLUMN_NAMES, min_size=0, max_size=8),
    st.lists(st.lists(_CELLS, max_size=9), max_size=5),
    _SIDECARS,
    st.booleans(),
)
def test_data_files_raise_only_data_file_errors(header, rows, sidecar, bom):
    text = ("\ufeff" if bom else "") + "\n".join(",".join(r) for r in [header, *rows]) + "\n"
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "fuzz.csv")
        with open(path, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        if sidecar is not None:
            with open(os.path.join(d, "fuzz.json"), "w", encoding="utf-8") as fh:
                fh.write(sidecar)
        try:
            data = load_data(path)
        except DataFileError:
            return
    # what loads is usable: every number finite and in its column's range
    assert isinstance(data, Dataset) and len(data) > 0
    for name in ("theta_i", "theta_r", "phi_r", "brdf"):
        assert all(math.isfinite(v) for v in getattr(data, name))
    assert (data.brdf > 0).all()


# ----------------------------------------------------------------------------- fit specs
_SCENE_OK = scene.loads(
    'name = "x"\n[illumination]\ntheta_i_deg = 45\n[coating]\nindex = 1.5\n'
    '[substrate]\nindex = [1.37, 7.62]\ndistribution = "exponential"\nsigma = 0.1\n',
    "fuzz.toml",
)
_SPEC_TEXT = st.one_of(
    st.text(max_size=30),
    st.builds(
        lambda k, lo, hi, pr: f"{k}:{lo}:{hi}" + (f":{pr}" if pr else ""),
        st.sampled_from(
            ["sigma", "coating", "n", "k", "substrate.index[1]", "noise.brdf", "noise.P", "x.y", ""]
        ),
        st.sampled_from(["0", "0.01", "-1", "nan", "1e400", "a", ""]),
        st.sampled_from(["1", "0.5", "inf", "2", ""]),
        st.sampled_from(["", "log", "uniform", "x"]),
    ),
)


@FUZZ
@given(
    _values,
    st.lists(_SPEC_TEXT, max_size=3),
    st.lists(_SPEC_TEXT, max_size=3),
    st.lists(_SPEC_TEXT, max_size=2),
)
def test_fit_specs_raise_only_fit_spec_errors(fit_table, free, noise, exclude):
    assume(isinstance(fit_table, dict))
    raw = {**_SCENE_OK.raw, "fit": fit_table}
    try:
        sc = scene.from_dict(raw, "fuzz.toml")
    except SceneError:
        return
    try:
        spec = fitspec_from(sc, free or None, noise or None, None, exclude or None)
    except FitSpecError:
        return
    assert isinstance(spec, FitSpec) and spec.free


@FUZZ
@given(_SPEC_TEXT)
def test_free_and_exclude_texts_raise_only_fit_spec_errors(text):
    for parse in (parse_free, parse_exclude):
        try:
            parse(text)
        except FitSpecError:
            pass
