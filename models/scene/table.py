"""The one table from scene-file names to model classes.

A scene file names a slope distribution (``distribution = "gaussian"``, in ``[substrate]``
and ``[coating.roughness]``) or a substrate model (``[substrate] model = "maxwell-beard"``).
:data:`TABLE` maps each name to the class it stands for and the keys a file may give; a key
is the class's declared parameter (or one of its old names, see
:class:`scatterbench.models.params.Alias`), and a key ending in ``_deg`` is the parameter without the
suffix, given in degrees (the Python API is in radians).  The classes validate the values
themselves (:mod:`scatterbench.models.params`); :func:`build` names the file's key when they refuse one.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field

from ..facet import FacetBRDF
from ..maxwell_beard import MaxwellBeardBRDF
from ..phase import HenyeyGreenstein
from ..rough_diffuse import RoughDiffuseBRDF
from ..slopes import (
    AnisotropicExponentialSlopes,
    AnisotropicGaussianSlopes,
    AnisotropicGGXSlopes,
    ExponentialAngles,
    ExponentialSlopes,
    GaussianAngles,
    GaussianSlopes,
    GGXSlopes,
)
from ..varnished import VarnishedCookTorranceBRDF
from .assembly import cook_torrance_mechanisms, facet_mechanisms, maxwell_beard_mechanisms

__all__ = [
    "Entry",
    "KeyProblem",
    "TABLE",
    "DISTRIBUTIONS",
    "SUBSTRATE_MODELS",
    "VOLUME",
    "VOLUME_DEFAULTS",
    "parameter",
    "build",
]


class KeyProblem(ValueError):
    """A file key that is missing or whose value a class refuses (``key`` None: the table)."""

    def __init__(self, key, message):
        super().__init__(message)
        self.key, self.message = key, message


@dataclass(frozen=True)
class Entry:
    """What a scene-file name stands for.

    ``cls`` is the class built from the keys; ``keys`` the keys a file may give;
    ``required`` the keys that must be given (a tuple of keys: any one of them);
    ``defaults`` the scene's defaults where they differ from the class's (a default for an
    old name applies only when its parameter is not given by its own name);
    substrate models only: ``slopes`` says whether ``[substrate] distribution`` gives the
    class's slopes (``"optional"``, ``"required"``) or is not used (``"ignored"``), ``alone``
    that the model has no interface, so no ``[coating]`` or ``[volume]`` may come with it,
    and ``mechanisms`` turns the validated ``[substrate]`` into mechanisms.  A key's value,
    ``true``/``false`` included, is the class's to accept or refuse (:mod:`scatterbench.models.params`).
    """

    kind: str  # "distribution" or "model"
    cls: type
    keys: tuple = ()
    required: tuple = ()
    defaults: dict = field(default_factory=dict)
    slopes: str = "optional"
    alone: bool = False
    mechanisms: Callable | None = None


def _slopes(cls, *keys, required=("sigma",)):
    return Entry("distribution", cls, keys + ("coverage",), tuple((k,) for k in required))


_ANISOTROPIC = ("sigma_x", "sigma_y", "rotation_deg")

TABLE = {
    "exponential": _slopes(ExponentialSlopes, "sigma"),
    "gaussian": _slopes(GaussianSlopes, "sigma"),
    "anisotropic-exponential": _slopes(
        AnisotropicExponentialSlopes, *_ANISOTROPIC, required=_ANISOTROPIC[:2]
    ),
    "anisotropic-gaussian": _slopes(AnisotropicGaussianSlopes, *_ANISOTROPIC, required=_ANISOTROPIC[:2]),
    "gaussian-angle": _slopes(GaussianAngles, "sigma_deg", required=("sigma_deg",)),
    "exponential-angle": _slopes(ExponentialAngles, "sigma_deg", required=("sigma_deg",)),
    # GGX (Trowbridge-Reitz): a width alpha, not an rms slope (GGX's is infinite)
    "ggx": _slopes(GGXSlopes, "alpha", required=("alpha",)),
    "anisotropic-ggx": _slopes(
        AnisotropicGGXSlopes, "alpha_x", "alpha_y", "rotation_deg", required=("alpha_x", "alpha_y")
    ),
    # [substrate] model = ...: "facet" takes its slopes from `distribution` (none: a flat
    # substrate); Cook-Torrance its own roughness, m (both m values) or m_parallel and
    # m_perpendicular (Eq. 19); Maxwell-Beard its specular facets' from `distribution`.
    # "facet" also takes `shadowing` (none | smith | smith-correlated, the facet models')
    "facet": Entry("model", FacetBRDF, ("shadowing",), mechanisms=facet_mechanisms),
    "cook-torrance": Entry(
        "model",
        VarnishedCookTorranceBRDF,
        ("m", "m_parallel", "m_perpendicular", "stroke_angle_deg", "convention")
        + ("normalization", "solid_angle", "shadowing"),
        required=(("m_parallel", "m"), ("m_perpendicular", "m")),
        defaults={"normalization": "energy", "solid_angle": "refracted"},
        slopes="ignored",
        mechanisms=cook_torrance_mechanisms,
    ),
    "maxwell-beard": Entry(
        "model",
        MaxwellBeardBRDF,
        ("rho_d", "rho_v", "tau_deg", "omega_deg", "polarized"),
        defaults={"polarized": True},
        slopes="required",
        alone=True,
        mechanisms=maxwell_beard_mechanisms,
    ),
}

#: [volume] keys and the declared parameters that validate them (the binder's index is the
#: coating's; ``single`` and ``interface`` are the scene's own choices), and the scene's defaults
VOLUME = {
    "rho": (RoughDiffuseBRDF, "rho"),
    "g": (HenyeyGreenstein, "g"),
    "polarized": (HenyeyGreenstein, "polarized"),
    "pairs": (RoughDiffuseBRDF, "pairs"),
    "seed": (RoughDiffuseBRDF, "seed"),
    "single_weight": (RoughDiffuseBRDF, "single"),
}
VOLUME_DEFAULTS = {"rho": 0.0, "g": 0.0, "polarized": True, "pairs": 5000, "seed": 0, "single_weight": 1.0}

#: distribution names and the classes (and the file keys) they map to
DISTRIBUTIONS = {name: (e.cls, e.keys) for name, e in TABLE.items() if e.kind == "distribution"}
#: the substrate models a scene may name
SUBSTRATE_MODELS = tuple(name for name, e in TABLE.items() if e.kind == "model")


def parameter(key: str) -> str:
    """The declared parameter a file key sets (``rotation_deg`` -> ``rotation``)."""
    return key[:-4] if key.endswith("_deg") else key


def build(name: str, table: dict, **given):
    """``(instance, params)``: the class ``name`` stands for, built from the file's ``table``
    (defaults applied, degrees converted) and the keyword arguments ``given`` by the scene,
    and the declared parameters the file's keys set, as the instance holds them (old names
    resolved), for building the models later.

    Raises :class:`KeyProblem` naming the file key that is missing or refused.
    """
    entry = TABLE[name]
    for alternatives in entry.required:
        if not any(k in table for k in alternatives):
            alt = f" (or give {', '.join(alternatives[1:])})" if len(alternatives) > 1 else ""
            raise KeyProblem(alternatives[0], f"required for {entry.kind} {name!r}{alt}")
    kwargs = {}
    for key in entry.keys:
        if key in table:
            kwargs[parameter(key)] = _file_value(key, table[key])
    for key, value in entry.defaults.items():
        if key not in kwargs and _target(entry.cls, key) not in kwargs:
            kwargs[key] = value
    try:
        instance = entry.cls(**kwargs, **given)
    except ValueError as exc:
        raise KeyProblem(_key_named(str(exc), entry), str(exc) + _degrees_note(exc, entry, table)) from exc
    targets = dict.fromkeys(_target(entry.cls, parameter(k)) for k in entry.keys)
    return instance, {t: getattr(instance, t) for t in targets}


def _file_value(key, value):
    if not key.endswith("_deg"):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise KeyProblem(key, f"must be a finite number of degrees; got {value!r}")
    return math.radians(value)


def _target(cls, name):
    """The declared parameter ``name`` sets (itself, or the target of an old name)."""
    return cls._alias(name).target if name in cls.aliases else name


def _key_named(message, entry):
    """The file key an error message is about: the parameter (or old name) it starts with."""
    head = re.match(r"[A-Za-z_]+", message)
    word = head.group(0) if head else ""
    for key in entry.keys:
        if parameter(key) == word:
            return key
    return None


def _degrees_note(exc, entry, table):
    key = _key_named(str(exc), entry)
    if key is None or not key.endswith("_deg"):
        return ""
    return f" ({key} = {table[key]!r} deg in the file, converted to radians)"
