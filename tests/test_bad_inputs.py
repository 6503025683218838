"""Bad inputs, table-driven: every one refused clearly, or handled with a finite, correct result.

Each row runs ``scatterbench`` in-process (``validation.cli.main``) in a fresh folder
holding a good scene (``s.toml``) and data file (``d.csv``) plus the row's own files,
and asserts either a refusal (exit 2, an ``error:`` line naming the file, key or flag,
no traceback) or success with the row's check.  A few rows call the Python API
(nightly history handling).  ``python -m pytest tests/test_bad_inputs.py`` runs them;
``CLASSES`` counts them by class.
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
from dataclasses import dataclass, field

import pytest
from command_files import DATA, FACETS, FAST, HEAD, ILL, ROWS, SCENE

from scatterbench.validation.cli import main

HEAD_S = "theta_i_deg,theta_r_deg,phi_r_deg,brdf\n"  # incident from a sidecar
STUDY = FAST[:-1]  # the studies have no --no-plots
NESTED = "[" * 5000 + "]" * 5000
HUGE = "9" * 400  # an integer that overflows a float


@dataclass
class Case:
    cls: str
    name: str
    argv: list | None = None  # the command line; or ``run(folder) -> (code, stdout, stderr)``
    files: dict = field(default_factory=dict)  # name -> str | bytes | None (None: a folder)
    words: tuple = ()  # each in stderr (a tuple inside: any one of them)
    code: int = 2
    check: object = None  # for a success: check(folder, stdout, stderr)
    run: object = None


CASES: list[Case] = []


def case(*args, **kw):
    CASES.append(Case(*args, **kw))


def top(line, text=FACETS):
    """``text`` with ``line`` among its top-level keys (before the first table: TOML puts a
    key after a table header into that table)."""
    return text.replace('name = "x"\n', f'name = "x"\n{line}\n', 1)


def scene_case(name, text, *words, fname="x.toml"):
    case("scene", name, ["scene", fname, "--out", "o"], {fname: text}, (fname, *words))


MISSING = object()


def data_case(name, body, *words, sidecar=None, extra=()):
    files = {} if body is MISSING else {"b.csv": body}
    if sidecar is not None:
        files["b.json"] = sidecar
    argv = ["fit", "b.csv", "--scene", "s.toml", "--out", "o", *FAST, *extra]
    case("data", name, argv, files, words)


def fit_case(name, extra, *words, files=None, data="d.csv"):
    argv = ["fit", data, "--scene", "s.toml", "--out", "o", *FAST, *extra]
    case("fit", name, argv, files or {}, words)


def spec_case(name, fit_table, *words, where="f.toml"):
    """A scene whose [fit] table is ``fit_table``; the error names ``where`` and ``words``."""
    text = FACETS + fit_table
    argv = ["fit", "d.csv", "--scene", "f.toml", "--out", "o", *FAST]
    case("fit", name, argv, {"f.toml": text}, (where, *words))


def cli_case(name, argv, *words, files=None):
    case("cli", name, argv, files or {}, words)


# ----------------------------------------------------------------------------- scene files
scene_case("toml syntax", 'name = "x"\n[illumination\n', ("x.toml:2:", "line 2"), "TOML")
scene_case("toml duplicate key", 'name = "x"\nname = "y"\n', ("x.toml:2:", "line 2"))
scene_case("toml bad value", 'name = "x"\n[illumination]\ntheta_i_deg = 4 5\n', ("x.toml:3:", "line 3"))
scene_case("not UTF-8", ILL.replace('"x"', '"caf\xe9"').encode("latin-1"), "UTF-8")
scene_case("NUL bytes", b'name = "x"\x00\n', ("x.toml:1:", "line 1"))
scene_case("empty file", "", "name")
scene_case("nested arrays", 'name = "x"\na = ' + NESTED + "\n", "nested")
scene_case("nested inline tables", 'name = "x"\na = ' + "{b = " * 3000 + "1" + "}" * 3000 + "\n", "nested")
scene_case("nested array in [fit]", FACETS + "[fit]\nfree = " + "[" * 50 + "]" * 50 + "\n", "nested")
scene_case("integer of 5000 digits", ILL + "[substrate]\nindex = " + "9" * 5000 + "\n", "index")
scene_case("name a number", ILL.replace('"x"', "3"), "name")
scene_case("name empty", ILL.replace('"x"', '""'), "name")
scene_case("name with a newline", ILL.replace('"x"', '"a\\nb,1,2"'), "name")
scene_case("name a table", "name = {a = 1}\n[illumination]\ntheta_i_deg = 45\n", "name")
scene_case("illumination a number", 'name = "x"\nillumination = 5\n', "illumination")
scene_case("illumination missing", 'name = "x"\n', "[illumination]")
scene_case("theta_i missing", 'name = "x"\n[illumination]\n', "theta_i_deg")
scene_case("theta_i a string", ILL.replace("45", '"45"'), "theta_i_deg")
scene_case("theta_i infinite", ILL.replace("45", "1e400"), "theta_i_deg")
scene_case("theta_i nan", ILL.replace("45", "nan"), "theta_i_deg")
scene_case("theta_i huge integer", ILL.replace("45", HUGE), "theta_i_deg")
scene_case("theta_i above 90", ILL.replace("45", "91"), "theta_i_deg")
scene_case("theta_i a bool", ILL.replace("45", "true"), "theta_i_deg")
scene_case("theta_i a table", ILL.replace("45", "{a = 1}"), "theta_i_deg")
scene_case("polarization a table", ILL + "polarization = {a = 1}\n", "polarization")
scene_case("polarization unknown", ILL + 'polarization = "sideways"\n', "polarization")
scene_case("polarization 3-vector", ILL + "polarization = [1, 0, 0]\n", "polarization")
scene_case("polarization unphysical", ILL + "polarization = [1, 2, 0, 0]\n", "polarization")
scene_case("polarization with a string", ILL + 'polarization = [1, "a", 0, 0]\n', "polarization")
scene_case("polarization linear:nan", ILL + 'polarization = "linear:nan"\n', "polarization")
scene_case("polarization linear:abc", ILL + 'polarization = "linear:abc"\n', "polarization")
scene_case("polarization linear:1e400", ILL + 'polarization = "linear:1e400"\n', "polarization")
scene_case("polarization bools", ILL + "polarization = [true, false, false, false]\n", "polarization")
scene_case("wavelength negative", ILL + "wavelength_nm = -5\n", "wavelength_nm")
scene_case("wavelength zero", ILL + "wavelength_nm = 0\n", "wavelength_nm")
scene_case("source unknown", ILL + 'source = "laser"\n', "source")
scene_case("point source without distance", ILL + 'source = "point"\n', "distance_mm")
scene_case(
    "distance for a collimated source", FACETS.replace("45\n", "45\ndistance_mm = 500\n"), "distance_mm"
)
scene_case(
    "radius above distance",
    ILL + 'source = "point"\ndistance_mm = 10\nsample_radius_mm = 20\n',
    "sample_radius_mm",
)
scene_case("unknown top-level key", top("colour = 1"), "colour")
scene_case("unknown illumination key", ILL + "theta_r_deg = 10\n", "theta_r_deg")
scene_case("substrate a number", top("substrate = 5", ILL), "substrate")
scene_case("substrate index missing", ILL + '[substrate]\ndistribution = "gaussian"\nsigma = 0.1\n', "index")
scene_case("index a word", FACETS.replace("index = 1.5", 'index = "glass"'), "index")
scene_case("index one element", FACETS.replace("index = 1.5", "index = [1.5]"), "index")
scene_case("index negative k", FACETS.replace("index = 1.5", "index = [1.5, -1]"), "index")
scene_case("index with a string", FACETS.replace("index = 1.5", 'index = [1.5, "a"]'), "index")
scene_case("index huge integer", FACETS.replace("index = 1.5", f"index = {HUGE}"), "index")
scene_case("index bools", FACETS.replace("index = 1.5", "index = [true, 0]"), "index")
scene_case("index a table", FACETS.replace("index = 1.5", "index = {n = 1.5}"), "index")
scene_case("distribution unknown", FACETS.replace('"gaussian"', '"lorentzian"'), "distribution")
scene_case("distribution a number", FACETS.replace('"gaussian"', "5"), "distribution")
scene_case(
    "distribution without sigma", ILL + '[substrate]\nindex = 1.5\ndistribution = "gaussian"\n', "sigma"
)
scene_case("sigma negative", FACETS.replace("0.2", "-0.1"), "sigma")
scene_case("sigma a string", FACETS.replace("0.2", '"0.2"'), "sigma")
scene_case("sigma infinite", FACETS.replace("0.2", "1e400"), "sigma")
scene_case("sigma huge integer", FACETS.replace("0.2", HUGE), "sigma")
scene_case("sigma a table", FACETS.replace("0.2", "{value = 0.2}"), "sigma")
scene_case("sigma a bool", FACETS.replace("0.2", "true"), "sigma")
scene_case("sigma_x for an isotropic law", FACETS + "sigma_x = 0.3\n", "sigma_x")
scene_case("sigma without a distribution", ILL + "[substrate]\nindex = 1.5\nsigma = 0.1\n", "sigma")
scene_case("rotation for an isotropic law", FACETS + "rotation_deg = 10\n", "rotation_deg")
scene_case(
    "anisotropic without sigma_y",
    ILL + '[substrate]\nindex = 1.5\ndistribution = "anisotropic-gaussian"\nsigma_x = 0.1\n',
    "sigma_y",
)
scene_case(
    "rotation huge integer",
    ILL
    + '[substrate]\nindex = 1.5\ndistribution = "anisotropic-gaussian"\nsigma_x = 0.1\nsigma_y = 0.2\n'
    + f"rotation_deg = {HUGE}\n",
    "rotation_deg",
)
scene_case("coverage above 1", FACETS + "coverage = 2\n", "coverage")
scene_case("model unknown", FACETS + 'model = "phong"\n', "model")
scene_case(
    "cook-torrance without m",
    ILL + '[substrate]\nmodel = "cook-torrance"\nindex = [2.29, 3.37]\n',
    "[substrate] m_parallel: required",
    "(or give m)",
)
CT = ILL + '[substrate]\nmodel = "cook-torrance"\nindex = [2.29, 3.37]\nm = 0.1\n'
scene_case("cook-torrance with a distribution", CT + 'distribution = "gaussian"\n', "distribution")
scene_case("cook-torrance with sigma", CT + "sigma = 0.1\n", "sigma")
scene_case("cook-torrance convention unknown", CT + 'convention = "fancy"\n', "convention")
scene_case(
    "cook-torrance m huge integer", CT.replace("m = 0.1", f"m = {HUGE}"), "[substrate] m: ", "too large"
)
scene_case("m for the facet model", FACETS + "m = 0.1\n", "[substrate] m: only for")
MB = ILL + '[substrate]\nmodel = "maxwell-beard"\nindex = 1.5\ndistribution = "gaussian"\nsigma = 0.05\n'
scene_case("maxwell-beard with a coating", MB + "[coating]\nindex = 1.5\n", "[coating]")
scene_case(
    "maxwell-beard without slopes",
    MB.replace('distribution = "gaussian"\nsigma = 0.05\n', ""),
    "distribution",
)
scene_case("maxwell-beard rho_d negative", MB + "rho_d = -1\n", "rho_d")
scene_case("maxwell-beard polarized a string", MB + 'polarized = "yes"\n', "polarized")
scene_case("coating a number", top("coating = 5"), "coating")
scene_case("coating without index", FACETS + "[coating]\n", "[coating] index")
scene_case("coating index below 1", FACETS + "[coating]\nindex = 0.5\n", "[coating] index")
scene_case("coating unknown key", FACETS + "[coating]\nindex = 1.5\nthickness = 3\n", "thickness")
scene_case("roughness a number", FACETS + "[coating]\nindex = 1.5\nroughness = 5\n", "roughness")
scene_case(
    "roughness without a distribution",
    FACETS + "[coating]\nindex = 1.5\n[coating.roughness]\nsigma = 0.1\n",
    "distribution",
)
scene_case("volume without a coating", FACETS + "[volume]\nrho = 0.5\n", "[volume]")
COATED = FACETS + "[coating]\nindex = 1.5\n"
scene_case("volume a number", top("volume = 5", COATED), "volume")
scene_case("volume rho above 1", COATED + "[volume]\nrho = 2\n", "rho")
scene_case("volume g = 1", COATED + "[volume]\ng = 1\n", "[volume] g: ")
scene_case("volume interface unknown", COATED + '[volume]\ninterface = "bumpy"\n', "interface")
scene_case("volume single a string", COATED + '[volume]\nsingle = "yes"\n', "single")
scene_case("volume pairs huge", COATED + f"[volume]\nrho = 0.5\npairs = {HUGE}\n", "pairs")
scene_case("volume pairs without Monte Carlo", COATED + "[volume]\nrho = 0.5\npairs = 100\n", "pairs")
scene_case("volume seed without Monte Carlo", COATED + "[volume]\nrho = 0.5\nseed = 3\n", "seed")
scene_case(
    "volume single_weight when single is off",
    COATED + "[volume]\nrho = 0.5\nsingle = false\nsingle_weight = 0.5\n",
    "single_weight",
)
scene_case("volume scatters nothing", COATED + "[volume]\nrho = 0\nsingle = false\n", "[volume]")
scene_case("detector a number", top("detector = 5"), "detector")
scene_case("aperture negative", FACETS + "[detector]\naperture_deg = -1\n", "aperture_deg")
scene_case("aperture 200 deg", FACETS + "[detector]\naperture_deg = 200\n", "aperture_deg")
scene_case("detector unknown key", FACETS + "[detector]\nfocus = 1\n", "focus")
scene_case("no mechanism at all", ILL + "[substrate]\nindex = 1.5\n", "no scattering mechanism")
scene_case("fit a number", top("fit = 5"), "fit")
case("scene", "scene file is a folder", ["scene", "sub", "--out", "o"], {"sub": None}, ("sub",))
case("scene", "scene file missing", ["scene", "nope.toml", "--out", "o"], {}, ("nope.toml",))


def _scene_outputs_parse(folder, out, err):
    """The CSV holds the data rows only: a name with commas and quotes injects nothing."""
    import csv

    with open(os.path.join(folder, "o", "x.csv"), newline="") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].startswith("#")]
    assert rows[0][0] == "scan" and {r[0] for r in rows[1:]} == {"in-plane", "out-of-plane"}
    assert all(len(r) == 8 for r in rows)


case(
    "scene",
    "name with commas and quotes is data",
    ["scene", "x.toml", "--out", "o"],
    {"x.toml": FACETS.replace('"x"', "'in-plane,45,1,2,3,4,5,6 \"q\"'")},
    code=0,
    check=_scene_outputs_parse,
)
case(
    "scene",
    "byte-order mark",
    ["scene", "x.toml", "--out", "o"],
    {"x.toml": "\ufeff" + FACETS},
    code=0,
    check=lambda folder, out, err: os.path.exists(os.path.join(folder, "o", "x.png")),
)

# ----------------------------------------------------------------------------- data files
data_case("missing file", MISSING, "b.csv")
data_case("a folder", None, "b.csv")
data_case("empty", "", "b.csv", "header")
data_case("header only", HEAD, "b.csv:1", "no data rows")
data_case(
    "unknown column", HEAD.replace("brdf,", "brdf,colour,") + "45,10,0,1,red,s\n", "b.csv:1:5", "colour"
)
data_case("duplicate column", HEAD.replace("brdf", "brdf,brdf") + "45,10,0,1,1,s\n", "b.csv:1:5", "twice")
data_case(
    "radian column name", HEAD.replace("theta_i_deg", "theta_i") + "1,10,0,1,s\n", "b.csv:1:1", "theta_i"
)
data_case("no brdf column", "theta_i_deg,theta_r_deg,phi_r_deg,incident\n45,10,0,s\n", "b.csv:1", "brdf")
data_case("brdf zero", HEAD + "45,10,0,0,s\n", "b.csv:2:4", "brdf")
data_case("brdf negative", HEAD + "45,10,0,-1,s\n", "b.csv:2:4", "brdf")
data_case("brdf nan", HEAD + "45,10,0,nan,s\n", "b.csv:2:4", "brdf")
data_case("brdf 1e400", HEAD + "45,10,0,1e400,s\n", "b.csv:2:4", "brdf")
data_case("brdf a word", HEAD + "45,10,0,abc,s\n", "b.csv:2:4", "brdf")
data_case("brdf empty", HEAD + "45,10,0,,s\n", "b.csv:2:4", "brdf")
data_case("too many fields", HEAD + "45,10,0,1,s,9\n", "b.csv:2", "fields")
data_case("too few fields", HEAD + "45,10,0\n", "b.csv:2", "fields")
data_case("theta_i 90", HEAD + "90,10,0,1,s\n", "b.csv:2:1", "theta_i_deg")
data_case("theta_r negative", HEAD + "45,-1,0,1,s\n", "b.csv:2:2", "theta_r_deg")
data_case("phi_r 400", HEAD + "45,10,400,1,s\n", "b.csv:2:3", "phi_r_deg")
data_case("s1 without s2, s3", HEAD.replace("brdf,", "brdf,s1,") + "45,10,0,1,0.1,s\n", "b.csv:1", "s2")
data_case(
    "Stokes and ellipsometric both",
    HEAD.replace("brdf,", "brdf,s1,s2,s3,P,") + "45,10,0,1,0,0,0,1,s\n",
    "b.csv:1",
    "not both",
)
data_case("P above 1.5", HEAD.replace("brdf,", "brdf,P,") + "45,10,0,1,2,s\n", "b.csv:2:5", "'P'")
data_case(
    "eta_err without eta",
    HEAD.replace("brdf,", "brdf,eta_err_deg,") + "45,10,0,1,1,s\n",
    "b.csv:1",
    "eta_err_deg",
)
data_case("incident missing", HEAD_S + "45,10,0,1\n", "b.csv:1", "incident")
data_case(
    "incident given twice",
    HEAD + "45,10,0,1,s\n",
    "b.csv:1",
    "twice",
    sidecar='{"incident_polarization": "s"}',
)
data_case("incident unknown", HEAD + "45,10,0,1,sideways\n", "b.csv:2:5", "incident")
data_case("incident linear:nan", HEAD + "45,10,0,1,linear:nan\n", "b.csv:2:5", "incident")
data_case("incident linear:abc", HEAD + "45,10,0,1,linear:abc\n", "b.csv:2:5", "incident")
data_case("NUL byte", (HEAD + "45,10,0,1\x00,s\n").encode(), "b.csv:2")
data_case("not UTF-8", (HEAD + "45,10,0,1,caf\xe9\n").encode("latin-1"), "b.csv:2", "UTF-8")
data_case("huge field", HEAD + "45,10,0," + "1" * 200000 + ",s\n", "b.csv:2")
data_case("sidecar not JSON", HEAD_S + "45,10,0,1\n", "b.json:1", "JSON", sidecar="{'a': 1}")
data_case("sidecar an array", HEAD_S + "45,10,0,1\n", "b.json", "object", sidecar="[1, 2]")
data_case("sidecar unknown key", HEAD + ROWS, "b.json:1", "colour", sidecar='{"colour": "red"}')
data_case("sidecar format", HEAD + ROWS, "b.json:1", "format", sidecar='{"format": "other/2"}')
data_case(
    "sidecar wavelength negative", HEAD + ROWS, "b.json:1", "wavelength_nm", sidecar='{"wavelength_nm": -1}'
)
data_case(
    "sidecar wavelength NaN token", HEAD + ROWS, "b.json:1", "wavelength_nm", sidecar='{"wavelength_nm": NaN}'
)
data_case(
    "sidecar wavelength huge integer",
    HEAD + ROWS,
    "b.json:1",
    "wavelength_nm",
    sidecar=f'{{"wavelength_nm": {HUGE}}}',
)
data_case(
    "sidecar integer of 5000 digits", HEAD + ROWS, "b.json", sidecar='{"wavelength_nm": ' + "9" * 5000 + "}"
)
data_case("sidecar aperture 100", HEAD + ROWS, "b.json:1", "aperture_deg", sidecar='{"aperture_deg": 100}')
data_case("sidecar truth a string", HEAD + ROWS, "b.json:1", "truth", sidecar='{"truth": "x"}')
data_case(
    "sidecar truth value a string",
    HEAD + ROWS,
    "b.json:1",
    "substrate.sigma",
    sidecar='{"truth": {"substrate.sigma": "abc"}}',
)
data_case(
    "sidecar truth value NaN",
    HEAD + ROWS,
    "b.json:1",
    "substrate.sigma",
    sidecar='{"truth": {"substrate.sigma": NaN}}',
)
data_case(
    "sidecar truth value a bool",
    HEAD + ROWS,
    "b.json:1",
    "substrate.sigma",
    sidecar='{"truth": {"substrate.sigma": true}}',
)
data_case(
    "sidecar incident a number",
    HEAD_S + "45,10,0,1\n",
    "b.json:1",
    "incident_polarization",
    sidecar='{"incident_polarization": 5}',
)
data_case(
    "sidecar incident 3-vector",
    HEAD_S + "45,10,0,1\n",
    "b.json:1",
    "incident_polarization",
    sidecar='{"incident_polarization": [1, 0, 0]}',
)
data_case(
    "sidecar incident an object",
    HEAD_S + "45,10,0,1\n",
    "b.json:1",
    "incident_polarization",
    sidecar='{"incident_polarization": {"a": 1}}',
)
data_case(
    "sidecar incident linear:nan",
    HEAD_S + "45,10,0,1\n",
    "b.json:1",
    "incident_polarization",
    sidecar='{"incident_polarization": "linear:nan"}',
)
data_case("sidecar nested", HEAD + ROWS, "b.json", "nested", sidecar='{"provenance": ' + NESTED + "}")
data_case("sidecar duplicate key", HEAD + ROWS, "b.json", "sample", sidecar='{"sample": "a", "sample": "b"}')
data_case("sidecar sample a number", HEAD + ROWS, "b.json:1", "sample", sidecar='{"sample": 5}')
data_case(
    "sidecar not UTF-8", HEAD + ROWS, "b.json", "UTF-8", sidecar='{"sample": "caf\xe9"}'.encode("latin-1")
)
data_case(
    "wavelength differs from the scene's",
    HEAD + ROWS,
    "wavelength",
    sidecar='{"wavelength_nm": 500}',
    extra=("--scene", "w.toml"),
)
CASES[-1].files["w.toml"] = SCENE.replace("45\n", "45\nwavelength_nm = 632.8\n", 1)
data_case("every row masked", HEAD + ROWS, "mask", extra=("--near-specular-deg", "180"))


def _fit_ok(folder, out, err):
    with open(os.path.join(folder, "o", "posterior.json")) as fh:
        text = fh.read()
    post = json.loads(text)
    assert "NaN" not in text and "Infinity" not in text
    assert math.isfinite(post["parameters"]["substrate.sigma"]["median"])


case(
    "data",
    "byte-order mark",
    ["fit", "b.csv", "--scene", "s.toml", "--out", "o", *FAST],
    {"b.csv": "\ufeff" + DATA},
    code=0,
    check=_fit_ok,
)
case(
    "data",
    "byte-order mark in the sidecar",
    ["fit", "b.csv", "--scene", "s.toml", "--out", "o", *FAST],
    {
        "b.csv": HEAD_S + ROWS.replace(",unpolarized", ""),
        "b.json": '\ufeff{"incident_polarization": "unpolarized"}',
    },
    code=0,
    check=_fit_ok,
)
case(
    "data",
    "CRLF line ends",
    ["fit", "b.csv", "--scene", "s.toml", "--out", "o", *FAST],
    {"b.csv": DATA.replace("\n", "\r\n")},
    code=0,
    check=_fit_ok,
)

# ----------------------------------------------------------------------------- fit settings and spec
fit_case("log prior from 0", ["--free", "sigma:0:1:log"], "substrate.sigma", "log")
fit_case("bounds reversed", ["--free", "sigma:1:0.1"], "substrate.sigma", "low < high")
fit_case("bound nan", ["--free", "sigma:nan:1"], "substrate.sigma", "nan")
fit_case("key not in the scene", ["--free", "nosuch.key:0:1"], "nosuch.key")
fit_case("no bounds", ["--free", "sigma"], "--free", "sigma")
fit_case("prior unknown", ["--free", "sigma:0.1:1:weird"], "prior")
fit_case("parameter twice", ["--free", "sigma:0.1:1", "--free", "sigma:0.1:2"], "twice")
fit_case("only noise free", ["--free", "noise.brdf:0.01:1"], "no free scene parameter")
fit_case("noise term unknown", ["--free", "sigma:0.1:1", "--free", "noise.foo:0:1"], "noise.foo")
fit_case("free noise of a missing column", ["--free", "sigma:0.1:1", "--free", "noise.P:0.01:0.1"], "noise.P")
fit_case(
    "free noise of a term off",
    ["--free", "sigma:0.1:1", "--free", "noise.P:0.01:0.1", "--noise", "P=off"],
    "noise.P",
)
fit_case("bound gives an invalid scene", ["--free", "sigma:-1:1"], "substrate.sigma", "-1")
fit_case("zero noise", ["--noise", "brdf=0"], "noise", "brdf")
fit_case("noise underflows", ["--noise", "brdf=1e-200"], "noise", "brdf")
fit_case("noise negative", ["--noise", "brdf=-1"], "brdf", ">= 0")
fit_case("noise nan", ["--noise", "brdf=nan"], "brdf", "nan")
fit_case("noise off for the BRDF", ["--noise", "brdf=off"], "brdf", "off")
fit_case("noise term unknown (fixed)", ["--noise", "foo=1"], "foo")
fit_case("noise without a value", ["--noise", "brdf"], "--noise", "brdf")
P_DATA = HEAD.replace("brdf,", "brdf,P,") + "".join(
    r.replace(",unpolarized", ",0.01,unpolarized") for r in ROWS.splitlines(keepends=True)
)
fit_case("zero P noise", ["--noise", "P=0"], "noise", "P", files={"p.csv": P_DATA}, data="p.csv")
fit_case("near-specular nan", ["--near-specular-deg", "nan"], "near_specular_deg")
fit_case("near-specular negative", ["--near-specular-deg", "-1"], "near_specular_deg")
fit_case("near-specular 200", ["--near-specular-deg", "200"], "near_specular_deg")
fit_case("exclude reversed", ["--exclude", "theta_r_deg=5:1"], "theta_r_deg", "lo <= hi")
fit_case("exclude unknown axis", ["--exclude", "foo=1:2"], "foo")
fit_case("exclude words", ["--exclude", "theta_r_deg=a:b"], "theta_r_deg")
fit_case("tau factor negative", ["--tau-factor", "-1"], "tau_factor")
fit_case("tau factor nan", ["--tau-factor", "nan"], "tau_factor")
fit_case("tau factor zero", ["--tau-factor", "0"], "tau_factor")
fit_case("walkers zero", ["--walkers", "0"], "walkers")
fit_case("walkers odd", ["--walkers", "3"], "walkers")
fit_case("walkers negative", ["--walkers", "-2"], "walkers")
fit_case("burn negative", ["--burn", "-5"], "burn must be an integer >= 0")
fit_case("walkers a word", ["--walkers", "abc"], "--walkers")
fit_case(
    "walkers too few for the free parameters",
    ["--walkers", "2", "--free", "sigma:0.1:1", "--noise", "brdf:0.01:1"],
    "walkers",
)
fit_case("step budget zero", ["--max-steps", "0"], "max_steps")
fit_case("step budget negative", ["--max-steps", "-5"], "max_steps")
fit_case("step budget 1e9 as text", ["--max-steps", "1e9"], "--max-steps")
fit_case("check interval zero", ["--check-every", "0"], "check_every")
fit_case("starts zero", ["--starts", "0"], "starts")
fit_case("seed negative", ["--seed", "-1"], "seed")
fit_case("workers zero", ["--workers", "0"], "--workers")
fit_case("workers negative", ["--workers", "-1"], "--workers")
fit_case("workers 100000", ["--workers", "100000"], "--workers")
fit_case("workers a word", ["--workers", "abc"], "--workers")
fit_case("scheduler not an address", ["--scheduler", "not an address"], "--scheduler")
fit_case(
    "workers and scheduler",
    ["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
    "--workers",
    "--scheduler",
)
fit_case("force and resume", ["--force", "--resume"], "--force", "--resume")
fit_case("resume without a checkpoint", ["--resume"], "o/chain.npz: no checkpoint")
fit_case("resume from garbage", ["--resume"], "chain.npz", files={"o/chain.npz": b"garbage"})
fit_case(
    "resume from a truncated zip",
    ["--resume"],
    "chain.npz",
    files={"o/chain.npz": b"PK\x03\x04" + b"\x00" * 40},
)
fit_case("resume from a folder", ["--resume"], "chain.npz", files={"o/chain.npz": None})
fit_case("out is a file", [], "--out o: not a folder", files={"o": "a file"})
fit_case(
    "out under a file", ["--out", "f/o"], "--out f/o: not a folder", "f is a file", files={"f": "a file"}
)
fit_case(
    "truth holds a string (refused before sampling)",
    [],
    "t.json",
    "truth",
    files={"t.csv": DATA, "t.json": '{"truth": {"substrate.sigma": "0.2"}}'},
    data="t.csv",
)
spec_case("[fit] free a string", '[fit]\nfree = "sigma:0.1:1"\n', "free")
spec_case("[fit] free entry a number", "[fit]\nfree = [5]\n", "free")
spec_case("[fit] free key a number", "[fit]\nfree = [{key = 5, low = 0.1, high = 1}]\n", "key")
spec_case(
    "[fit] free entry unknown key", '[fit]\nfree = [{key = "sigma", low = 0.1, high = 1, step = 2}]\n', "step"
)
spec_case("[fit] free bound a bool", '[fit]\nfree = [{key = "sigma", low = true, high = 1}]\n', "low")
spec_case(
    "[fit] free prior a number", '[fit]\nfree = [{key = "sigma", low = 0.1, high = 1, prior = 5}]\n', "prior"
)
spec_case("[fit] noise a number", '[fit]\nfree = ["sigma:0.1:1"]\nnoise = 5\n', "noise")
spec_case("[fit.noise] brdf a bool", '[fit]\nfree = ["sigma:0.1:1"]\n[fit.noise]\nbrdf = true\n', "brdf")
spec_case("[fit.noise] brdf a table", '[fit]\nfree = ["sigma:0.1:1"]\n[fit.noise]\nbrdf = {a = 1}\n', "brdf")
spec_case(
    "[fit.noise] brdf zero",
    '[fit]\nfree = ["sigma:0.1:1"]\n[fit.noise]\nbrdf = 0\n',
    "noise.brdf",
    where="d.csv",
)
spec_case(
    "[fit.mask] exclude a number",
    '[fit]\nfree = ["sigma:0.1:1"]\nnoise = {brdf = 0.05}\n[fit.mask]\nexclude = 5\n',
    "exclude",
)
spec_case(
    "[fit.mask] near_specular_deg a bool",
    '[fit]\nfree = ["sigma:0.1:1"]\nnoise = {brdf = 0.05}\n[fit.mask]\nnear_specular_deg = true\n',
    "near_specular_deg",
)
spec_case("[fit.mask] unknown key", '[fit]\nfree = ["sigma:0.1:1"]\n[fit.mask]\nbogus = 1\n', "bogus")
spec_case("[fit] unknown key", '[fit]\nfree = ["sigma:0.1:1"]\nsteps = 5\n', "steps")
spec_case("[fit.mask] a number", '[fit]\nfree = ["sigma:0.1:1"]\nmask = 5\n', "mask")

# ----------------------------------------------------------------------------- studies and other commands
REC = ["study", "recovery", "d.csv", "--scene", "s.toml", "--out", "r", "--injections", "1", *STUDY]
cli_case("recovery noise levels a word", [*REC, "--noise-levels", "abc"], "--noise-levels")
cli_case("recovery noise level negative", [*REC, "--noise-levels", "-0.1"], "--noise-levels")
cli_case("recovery noise level zero", [*REC, "--noise-levels", "0"], "--noise-levels")
cli_case("recovery noise level nan", [*REC, "--noise-levels", "nan"], "--noise-levels")
cli_case("recovery no noise level", [*REC, "--noise-levels", ","], "--noise-levels")
cli_case("recovery geometries zero", [*REC, "--n-geometries", "0"], "--n-geometries")
cli_case("recovery geometries negative", [*REC, "--n-geometries", "-3"], "--n-geometries")
cli_case("recovery geometries a word", [*REC, "--n-geometries", "abc"], "--n-geometries")
cli_case(
    "recovery injections negative", [*REC[: -len(STUDY) - 2], "--injections", "-1", *STUDY], "injections"
)
INV = ["study", "inversion", "d.csv", "--scene", "s.toml", "--out", "i"]
cli_case("inversion bins zero", [*INV, "--bins", "0"], "--bins")
cli_case("inversion bins negative", [*INV, "--bins", "-4"], "--bins")
cli_case("inversion bootstrap negative", [*INV, "--bootstrap", "-1"], "--bootstrap")
cli_case("inversion seed negative", [*INV, "--seed", "-1"], "--seed")
CMP = ["study", "compare", "d.csv", "--scene", "s.toml", "--out", "c", *STUDY[:-1]]  # nor --no-progress
cli_case("compare noise unknown", [*CMP, "--noise", "foo=1"], "foo")
cli_case("compare workers zero", [*CMP, "--workers", "0"], "--workers")
cli_case("compare out is a file", CMP, "--out c: not a folder", files={"c": "a file"})
cli_case("table1 tol nan", ["table1", "--tol", "nan"], "--tol")
cli_case("table1 tol zero", ["table1", "--tol", "0"], "--tol")
cli_case("table1 tol negative", ["table1", "--tol", "-1"], "--tol")
cli_case("table1 tol infinite", ["table1", "--tol", "inf"], "--tol")
cli_case("scene tol nan", ["scene", "s.toml", "--out", "o", "--tol", "nan"], "--tol")
cli_case("scene tol zero", ["scene", "s.toml", "--out", "o", "--tol", "0"], "--tol")
cli_case(
    "scene out is a file", ["scene", "s.toml", "--out", "o"], "--out o: not a folder", files={"o": "a file"}
)
cli_case("tradeoff tol negative", ["tradeoff", "--tol", "-1"], "--tol")
cli_case(
    "tradeoff out is a file",
    ["tradeoff", "--quick", "--out", "o"],
    "--out o: not a folder",
    files={"o": "a file"},
)
cli_case(
    "validate json into a file's folder",
    ["validate", "--quick", "--json", "f/x.json"],
    "/f: not a folder",
    files={"f": "a file"},
)
cli_case("validate json is a folder", ["validate", "--quick", "--json", "sub"], "sub", files={"sub": None})
cli_case(
    "report out is a file",
    ["report", "--quick", "--out", "o"],
    "--out o: not a folder",
    files={"o": "a file"},
)
cli_case("check model without a colon", ["check", "scatterbench.models"], "MODULE:NAME")
cli_case("check model module missing", ["check", "nosuch_module_x:Model"], "nosuch_module_x")
cli_case("check model name missing", ["check", "scatterbench.models:NoSuchModel"], "NoSuchModel")
cli_case(
    "check unknown check name", ["check", "scatterbench.models:FacetBRDF", "--checks", "nosuch"], "nosuch"
)
cli_case(
    "check json is a folder",
    ["check", "scatterbench.models:FacetBRDF", "--json", "sub"],
    "--json",
    files={"sub": None},
)
cli_case(
    "check json in a file's folder",
    ["check", "scatterbench.models:FacetBRDF", "--json", "f/x.json"],
    "/f: not a folder",
    files={"f": "a file"},
)
cli_case("stability workers zero", ["stability", "--workers", "0"], "--workers")
cli_case(
    "stability workers and scheduler",
    ["stability", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
    "--workers",
    "--scheduler",
)
cli_case("unknown command", ["frobnicate"], "frobnicate")
cli_case("no command", [], "command")
cli_case("fit without --scene", ["fit", "d.csv", "--out", "o"], "--scene")


# ----------------------------------------------------------------------------- nightly history
def _nightly(folder, **kw):
    """The nightly API on a tiny report (no section, no check): ``(code, stdout, stderr)``."""
    from scatterbench.validation.report import nightly

    res = nightly(os.path.join(folder, "h"), quick=True, only=[], checks=[], **kw)
    return res[0], "\n".join(map(str, res)), ""


def _history_cli(*extra):
    return ["nightly", "--history", "h", "--quick", *extra]


case("nightly", "history is a file", _history_cli(), {"h": "a file"}, ("h: not a folder",))
case("nightly", "latest is a folder", _history_cli(), {"h/runs": None, "h/latest": None}, ("latest",))
case("nightly", "latest is a file", _history_cli(), {"h/runs": None, "h/latest": "x"}, ("latest",))
case("nightly", "runs is a file", _history_cli(), {"h/runs": "x"}, ("runs",))
case("nightly", "wait negative", _history_cli("--wait", "-1"), {}, ("--wait",))
case("nightly", "wait nan", _history_cli("--wait", "nan"), {}, ("--wait",))


def _corrupt_previous(folder):
    _nightly(folder, stamp="2026-01-01T000000Z")
    with open(os.path.join(folder, "h", "runs", "2026-01-01T000000Z", "results.json"), "w") as fh:
        fh.write('{"checks": [')
    return _nightly(folder, stamp="2026-01-02T000000Z")


case("nightly", "corrupt previous results.json", run=_corrupt_previous, code=1, words=("results.json", "not"))


def _previous_not_an_object(folder):
    _nightly(folder, stamp="2026-01-01T000000Z")
    with open(os.path.join(folder, "h", "runs", "2026-01-01T000000Z", "results.json"), "w") as fh:
        fh.write("[1, 2]")
    return _nightly(folder, stamp="2026-01-02T000000Z")


case(
    "nightly",
    "previous results.json not an object",
    run=_previous_not_an_object,
    code=1,
    words=("results.json",),
)


def _dangling_latest(folder):
    os.makedirs(os.path.join(folder, "h", "runs"))
    os.symlink("runs/gone", os.path.join(folder, "h", "latest"))
    code, out, err = _nightly(folder, stamp="2026-01-02T000000Z")
    assert os.path.exists(os.path.join(folder, "h", "latest", "results.json"))
    return code, out, err


case("nightly", "latest points nowhere", run=_dangling_latest, code=1, words=("latest",))


def _stamp_collision(folder):
    a = _nightly(folder, stamp="2026-01-01T000000Z")
    b = _nightly(folder, stamp="2026-01-01T000000Z")
    runs = sorted(os.listdir(os.path.join(folder, "h", "runs")))
    assert a[0] == b[0] == 0 and len(runs) == 2, runs
    latest = os.path.realpath(os.path.join(folder, "h", "latest"))
    assert os.path.basename(latest) == runs[-1] != "2026-01-01T000000Z"
    return 0, "", ""


case("nightly", "stamp collision", run=_stamp_collision, code=0)


def _bad_stamp(folder):
    return _nightly(folder, stamp="../escape")


def _api_error(fn):
    def run(folder):
        try:
            return fn(folder)
        except ValueError as exc:  # the API refuses with a ValueError; the CLI turns it into exit 2
            return 2, "", f"error: {exc}"

    return run


case("nightly", "stamp with a slash", run=_api_error(_bad_stamp), words=("stamp",))


def _killed_leftovers(folder):
    os.makedirs(os.path.join(folder, "h", "runs"))
    os.makedirs(os.path.join(folder, "h", ".tmp-2026-01-01T000000Z", "half"))
    code, out, err = _nightly(folder)
    assert not [n for n in os.listdir(os.path.join(folder, "h")) if n.startswith(".tmp-")]
    return code, out, err


case("nightly", "leftover of a killed run", run=_killed_leftovers, code=0)


def _lock_held(folder):
    """Another process holds the history's lock: with --wait 0 the run refuses at once."""
    import subprocess

    os.makedirs(os.path.join(folder, "h"))
    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLD_LOCK, os.path.join(folder, "h", ".lock")],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        from scatterbench.validation.report import nightly

        try:
            nightly(os.path.join(folder, "h"), quick=True, only=[], checks=[], wait=0)
        except ValueError as exc:
            return 2, "", f"error: {exc}"
        return 0, "", ""
    finally:
        holder.kill()
        holder.wait()


_HOLD_LOCK = """
import sys, time
from scatterbench.validation.atomic import file_lock
with file_lock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(60)
"""
case(
    "nightly", "history locked by another run", run=_lock_held, words=(".lock", "another nightly run", "pid")
)


def _read_only_folder(folder):
    """A folder this process cannot write to (chmod for a normal user; /sys for root)."""
    ro = os.path.join(folder, "ro")
    os.makedirs(ro)
    os.chmod(ro, 0o555)
    probe = os.path.join(ro, ".probe")
    try:
        open(probe, "w").close()
        os.unlink(probe)
    except OSError:
        return ro
    for cand in ("/sys", "/proc/sys"):
        try:
            open(os.path.join(cand, ".scatterbench-probe"), "w").close()
        except OSError:
            return cand
    return None


def _read_only_history(folder):
    ro = _read_only_folder(folder)
    if ro is None:
        pytest.skip("no read-only folder on this machine")
    return _capture(["nightly", "--history", ro, "--quick"])


case("nightly", "read-only history", run=_read_only_history, words=(("ro", "/sys", "/proc/sys"), "writ"))


def _read_only_out(folder):
    ro = _read_only_folder(folder)
    if ro is None:
        pytest.skip("no read-only folder on this machine")
    return _capture(["scene", "s.toml", "--out", os.path.join(ro, "o")])


case("cli", "read-only output folder", run=_read_only_out, words=("writ",))


# ----------------------------------------------------------------------------- the runner
def _write_files(folder, files):
    base = {"s.toml": SCENE, "d.csv": DATA}
    base.update(files)
    for name, content in base.items():
        p = os.path.join(folder, name)
        os.makedirs(os.path.dirname(p), exist_ok=True)
        if content is None:
            os.makedirs(p, exist_ok=True)
        elif isinstance(content, bytes):
            with open(p, "wb") as fh:
                fh.write(content)
        else:
            with open(p, "w", encoding="utf-8", newline="") as fh:
                fh.write(content)


def _capture(argv):
    """``main(argv)`` with stdout and stderr captured: ``(code, stdout, stderr)``; an exception
    escaping ``main`` is a failure of the row, reported with its type."""
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # an argparse refusal, if main lets it through
            code = exc.code
        except BaseException as exc:  # noqa: BLE001 - a crash is what the row detects
            code = f"escaped {type(exc).__name__}: {exc}"[:300]
    return code, out.getvalue(), err.getvalue()


def run_case(c: Case, folder):
    _write_files(folder, c.files)
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        if c.run is not None:
            try:
                return c.run(folder)
            except pytest.skip.Exception:
                raise
            except BaseException as exc:  # noqa: BLE001
                return f"escaped {type(exc).__name__}: {exc}"[:300], "", ""
        return _capture(c.argv)
    finally:
        os.chdir(cwd)


def judge(c: Case, code, out, err):
    """``None`` if the row was handled as it should be, else what went wrong."""
    if "Traceback" in err:
        return "a traceback on stderr"
    if code != c.code:
        return f"exit {code!r}, expected {c.code} (stderr: {err.strip()[-200:]!r})"
    if c.code == 2 or c.words:
        text = err if c.code == 2 else err + out
        if c.code == 2 and not re.search(r"(^|: )error: ", text, re.M):
            return f"no 'error:' line: {err!r}"
        for w in c.words:
            alts = w if isinstance(w, tuple) else (w,)
            if not any(a in text for a in alts):
                return f"the message does not name {' or '.join(map(repr, alts))}: {text.strip()[-300:]!r}"
    return None


CLASSES = sorted({c.cls for c in CASES})


def test_at_least_120_bad_inputs_across_the_classes():
    counts = {k: sum(c.cls == k for c in CASES) for k in CLASSES}
    assert sum(counts.values()) >= 120 and set(counts) == {"scene", "data", "fit", "cli", "nightly"}, counts
    assert len({(c.cls, c.name) for c in CASES}) == len(CASES)


@pytest.mark.parametrize("c", CASES, ids=[f"{c.cls}: {c.name}" for c in CASES])
def test_bad_input(c, tmp_path):
    code, out, err = run_case(c, str(tmp_path))
    problem = judge(c, code, out, err)
    assert problem is None, problem
    if c.check is not None:
        assert c.check(str(tmp_path), out, err) is not False
