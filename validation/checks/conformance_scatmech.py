"""The conformance check against SCATMECH, for a model that names its SCATMECH equivalent.

A model sets ``scatmech = (name, parameters)`` with SCATMECH's own model name and
parameter strings (DESIGN.md "Reference implementation"), e.g.
``("Facet_BRDF_Model", {"substrate": "(1.37,7.62)", "sdf":
"Exponential_Slope_Distribution_Function", "sdf.s": 0.05})``.  Where pySCATMECH is
installed the kit evaluates that model live; elsewhere (CI) it uses the committed SCATMECH
reference values (``references/data/scatmech_*.csv``) made with the same parameters, if
any were.
"""

from __future__ import annotations

import math
import re
from functools import cache

import numpy as np

from scatterbench import references
from scatterbench.validation.numerics.probes import random_geometries

from .conformance import claims, model_check, mueller_of, skipped, verdict, where

__all__ = [
    "SCATMECH_TOL",
    "SCATMECH_ARITHMETIC",
    "EXPONENT_MAX",
    "SCATMECH_DEFAULT_TOL",
    "SCATMECH_FLOOR",
    "scatmech_tolerance",
    "committed_cases",
    "matching_cases",
    "normalized",
]

#: SCATMECH's own float64 arithmetic differs from scatterbench's by at most this
#: ``|M - M_scatmech| / M00`` per unit of the slope density's exponent ``x = -ln(P3/P3_max)``
#: (``max(1, x)`` units): the density ``exp(-x)`` turns a relative rounding ``e`` of its
#: argument into ``x e``.  Measured 1.58e-12 at the 590 committed facet cases above the floor,
#: x from < 1 to 498; the constant keeps a factor 2 over it
#: (tests/test_conformance.py::test_scatmech_residual_per_unit_exponent asserts the bound).
SCATMECH_ARITHMETIC = 3.2e-12
#: the largest exponent of a case compared relatively: ``M00 >= SCATMECH_FLOOR = 1e-250`` and
#: a peak below 1e20 (slope widths >= 1e-8, models.params) give ``x <= ln(1e270) ~ 622``
EXPONENT_MAX = 622.0

#: max ``|M - M_scatmech| / M00`` per SCATMECH model: one table for the registry's SCATMECH
#: checks (:mod:`scatterbench.validation.checks.seed000`, :mod:`scatterbench.validation.checks.seed003`) and the kit's ``scatmech`` check
SCATMECH_TOL = {
    # a slope density exp(-x): the arithmetic's bound at the largest exponent compared (2.0e-9)
    "Facet_BRDF_Model": SCATMECH_ARITHMETIC * EXPONENT_MAX,
    "Subsurface_Facet_BRDF_Model": SCATMECH_ARITHMETIC * EXPONENT_MAX,
    "Shadowed_Facet_BRDF_Model": SCATMECH_ARITHMETIC * EXPONENT_MAX,
    # SCATMECH tabulates the internal reflectance average R-bar (seed 003 Eq. 22) on a
    # 0.2-deg grid; scatterbench integrates it exactly, and the diffuse values inherit the
    # table's error through 1 / (1 - rho R-bar), largest at rho = 1 (seed003.check_scatmech_seed003
    # prints the R-bar offset)
    "Diffuse_Subsurface_BRDF_Model": 2e-3,
    # no slope density (x = 0): the arithmetic's bound itself
    "First_Diffuse_BRDF_Model": SCATMECH_ARITHMETIC,
}
#: the limit for a SCATMECH model the table does not name: nothing is known of its internals
#: (a table like Diffuse_Subsurface's, an iteration), so only a formula error is flagged
SCATMECH_DEFAULT_TOL = 1e-6
#: below this SCATMECH M00 a case is compared absolutely: the slope densities flush
#: exp(-x) to an exact zero for x > 700 (models.slopes._exp_neg), SCATMECH keeps ~1e-300
SCATMECH_FLOOR = 1e-250


def scatmech_tolerance(name):
    """The limit of ``max |M - M_scatmech| / M00`` against SCATMECH model ``name``."""
    return SCATMECH_TOL.get(name, SCATMECH_DEFAULT_TOL)


#: SCATMECH defaults of the parameters the committed files set explicitly
_DEFAULTS = {"Facet_BRDF_Model": {"type": 0}}

_PAIR = re.compile(r"^\(\s*([^,()]+)\s*,\s*([^,()]+)\s*\)$")


def _value(v):
    """A parameter value as a comparable number (``"(n,k)"`` -> complex) or a string."""
    if isinstance(v, bool):
        return v
    if isinstance(v, int | float | complex):
        return complex(v)
    s = str(v).strip()
    m = _PAIR.match(s)
    try:
        return complex(float(m[1]), float(m[2])) if m else complex(float(s))
    except ValueError:
        return s


def normalized(name, params):
    """``(name, {key: value})`` with SCATMECH's defaults filled in and values comparable."""
    full = {**_DEFAULTS.get(name, {}), **params}
    return name, {k: _value(v) for k, v in full.items()}


def _same(a, b):
    if isinstance(a, complex) and isinstance(b, complex):
        return abs(a - b) <= 1e-12 * max(abs(a), abs(b), 1e-300)
    return a == b


def _sdf(name):
    return f"{name}_Slope_Distribution_Function"


def _facet_cases():
    ref = references.scatmech_facet()
    for i in range(len(ref["model"])):
        sub = complex(ref["substrate_n"][i], ref["substrate_k"][i])
        p = {"substrate": sub, "sdf": _sdf(ref["sdf"][i]), "sdf.s": ref["sigma"][i]}
        if ref["model"][i] == "facet":
            yield "Facet_BRDF_Model", {**p, "type": 0}, ref, i
        else:
            yield "Subsurface_Facet_BRDF_Model", {**p, "overcoat": complex(ref["coating"][i])}, ref, i


def _seed003_params(kind, ref, i):
    sub = complex(ref["n"][i], ref["k"][i] if "k" in ref else 0.0)
    if kind == "diffuse":
        return "Diffuse_Subsurface_BRDF_Model", {"substrate": sub, "reflectance.table": ref["rho"][i]}
    if kind == "single":
        return "First_Diffuse_BRDF_Model", {
            "substrate": sub,
            "phase_function": "Unpolarized_Phase_Function",
            "phase_function.phase_function": "Henyey_Greenstein_Phase_Function",
            "phase_function.phase_function.g": ref["g"][i],
            "phase_function.log_absorption": -1000,
        }
    p = {"substrate": sub, "sdf": _sdf(ref["sdf"][i]), "sdf.s": ref["sigma"][i]}
    if kind == "btdf":
        return "Facet_BRDF_Model", {**p, "type": 1}
    shadow = {
        "shadow": "Maxwell_Beard_Shadow_Function",
        "shadow.tau": ref["tau"][i],
        "shadow.Omega": ref["omega"][i],
    }
    return "Shadowed_Facet_BRDF_Model", {**p, **shadow}


@cache
def committed_cases():
    """Every committed SCATMECH reference value: ``(name, params, ti, tr, pr, M)`` with the
    parameters as the generating scripts (``references/scripts``) passed them."""
    out = []
    for name, params, ref, i in _facet_cases():
        out.append(
            (
                *normalized(name, params),
                ref["theta_i"][i],
                ref["theta_r"][i],
                ref["phi_r"][i],
                ref["mueller"][i],
            )
        )
    for kind in ("diffuse", "single", "btdf", "mb"):
        ref = references.scatmech_seed003(kind)
        for i in range(len(ref["theta_i"])):
            name, params = _seed003_params(kind, ref, i)
            row = (ref["theta_i"][i], ref["theta_r"][i], ref["phi_r"][i], ref["mueller"][i])
            out.append((*normalized(name, params), *row))
    return tuple(out)


def matching_cases(name, params):
    """``(ti, tr, pr, M)`` arrays of the committed cases of SCATMECH model ``name`` with
    exactly these parameters (after SCATMECH's defaults), or ``None``."""
    name, want = normalized(name, params)
    rows = [
        c[2:]
        for c in committed_cases()
        if c[0] == name and c[1].keys() == want.keys() and all(_same(c[1][k], want[k]) for k in want)
    ]
    if not rows:
        return None
    ti, tr, pr, M = zip(*rows, strict=True)
    return np.array(ti), np.array(tr), np.array(pr), np.array(M)


def _live(name, params):
    """``(ti, tr, pr, M)`` from a live pySCATMECH at 40 seeded geometries, or ``None``."""
    try:
        from pySCATMECH.brdf import (
            BRDF_Model,  # pySCATMECH (optional peer: most machines have only the committed data)
        )
    except ImportError:
        return None
    ref = BRDF_Model(name, **{k: v if isinstance(v, str) else repr(v) for k, v in params.items()})
    ti, tr, pr = random_geometries(40, seed=11, max_deg=80.0)
    M = np.array(
        [np.array(ref.MuellerBRDF(a, b, c), dtype=float) for a, b, c in zip(ti, tr, pr, strict=True)]
    )
    return ti, tr, pr, M


def _declared(model):
    decl = claims(model, "scatmech", None)
    if decl is None:
        return None
    if not (
        isinstance(decl, tuple | list)
        and len(decl) == 2
        and isinstance(decl[0], str)
        and isinstance(decl[1], dict)
    ):
        raise ValueError(f"scatmech must be a (name, parameters dict) pair; got {decl!r}")
    return decl[0], dict(decl[1])


@model_check(
    tests="DESIGN.md: a model's Mueller matrix agrees with SCATMECH's MuellerBRDF(ti, tr, pr) element by "
    "element (live pySCATMECH, else the committed reference values made with the same parameters)"
)
def check_scatmech(model, ctx):
    decl = _declared(model)
    if decl is None:
        return skipped("scatmech", "the model names no SCATMECH equivalent (scatmech attribute)")
    data, source = _live(*decl), "live pySCATMECH"
    if data is None:
        data, source = matching_cases(*decl), "committed SCATMECH reference values"
    if data is None:
        why = f"pySCATMECH is not installed and no committed reference values were made with {decl[0]} {decl[1]}"
        return skipped("scatmech", why)
    ti, tr, pr, R = data
    M = np.asarray(mueller_of(model, ti, tr, pr)).reshape(-1, 4, 4)
    e = np.max(np.abs(M - R), axis=(-1, -2)) / np.maximum(R[:, 0, 0], SCATMECH_FLOOR)
    e = np.where(np.isfinite(e), e, math.inf)
    k = int(np.argmax(e))
    detail = f"max |M - M_scatmech| / M00 over {len(e)} geometries ({source}; {decl[0]})"
    tol = scatmech_tolerance(decl[0])
    return verdict("scatmech", float(e[k]), tol, detail, where=where(ti, tr, pr, k))
