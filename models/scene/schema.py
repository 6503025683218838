"""Scene TOML schema: the tables and keys a scene file may hold, validated into plain data.

The scene checks what is its own: the tables and keys that exist, which ones are
required, and combinations (a ``[volume]`` needs a ``[coating]``, Maxwell-Beard stands
alone).  Values that a model takes are validated by that model's declared parameters
(:mod:`models.params`, through :mod:`models.scene.table`); every error is a
:class:`SceneError` naming the file, the key and the allowed values.
"""

from __future__ import annotations

import math

from ..aperture import DetectorAperture
from ..point_source import PointSourceBRDF
from ..polarization import stokes
from ..subsurface_facet import SubsurfaceFacetBRDF
from .table import SUBSTRATE_MODELS, TABLE, VOLUME, VOLUME_DEFAULTS, KeyProblem, build

__all__ = ["SceneError", "parse"]

_TOP = {"name", "description", "illumination", "coating", "substrate", "volume", "detector", "fit"}
_ILLUM = {"theta_i_deg", "polarization", "wavelength_nm", "source", "distance_mm", "sample_radius_mm"}
_SUBSTRATE_KEYS = {"index", "distribution", "model"} | {k for e in TABLE.values() for k in e.keys}


class SceneError(ValueError):
    """A scene file problem; the message names the file, the key and the allowed values."""


def parse(data: dict, path: str) -> dict:
    """The validated fields of :class:`models.scene.Scene` from the dict a TOML file parses to."""
    _unknown(path, "", data, _TOP)
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise _err(path, "name", "a non-empty string is required")
    out = {"name": name, **_illumination(path, data.get("illumination"))}
    out["coating"] = _coating(path, data["coating"]) if "coating" in data else None
    out["substrate"] = _substrate(path, data["substrate"], data) if "substrate" in data else None
    out["volume"] = _volume(path, data["volume"], out["coating"]) if "volume" in data else None
    out["detector"] = _detector(path, data["detector"]) if "detector" in data else None
    out["fit"] = data.get("fit")
    return out


def _err(path, key, msg):
    return SceneError(f"{path}: {key}: {msg}")


def _unknown(path, section, table, allowed):
    if not isinstance(table, dict):
        raise _err(path, section.strip() or "scene", "must be a table")
    for k in table:
        if k not in allowed:
            raise _err(path, f"{section}{k}", f"unknown key; allowed: {', '.join(sorted(allowed))}")


def _number(path, key, value, low=None, high=None, low_open=False):
    """A quantity of the scene itself (not a model parameter): a finite number in range."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _err(path, key, f"must be a finite number; got {value!r}")
    if low is not None and (value < low or (low_open and value == low)):
        raise _err(path, key, f"must be {'>' if low_open else '>='} {low:g}; got {value!r}")
    if high is not None and value > high:
        raise _err(path, key, f"must be <= {high:g}; got {value!r}")
    return float(value)


def _declared(path, key, cls, name, value):
    """``value`` validated by the declared parameter ``name`` of ``cls``, errors naming ``key``."""
    try:
        return cls.check_parameter(name, value)
    except ValueError as exc:
        raise _err(path, key, str(exc)) from exc


def _flag(path, key, value):
    if not isinstance(value, bool):
        raise _err(path, key, f"must be true or false; got {value!r}")
    return value


def _illumination(path, ill):
    if not isinstance(ill, dict):
        raise _err(path, "[illumination]", "the table is required (theta_i_deg at least)")
    _unknown(path, "[illumination] ", ill, _ILLUM)
    if "theta_i_deg" not in ill:
        raise _err(path, "[illumination] theta_i_deg", "required, in [0, 90]")
    out = {
        "theta_i": math.radians(_number(path, "[illumination] theta_i_deg", ill["theta_i_deg"], 0.0, 90.0))
    }
    try:
        out["polarization"] = tuple(float(x) for x in stokes(ill.get("polarization", "unpolarized")))
    except ValueError as exc:
        raise _err(path, "[illumination] polarization", str(exc)) from exc
    wl = ill.get("wavelength_nm")
    out["wavelength_nm"] = (
        None if wl is None else _number(path, "[illumination] wavelength_nm", wl, 0.0, low_open=True)
    )
    source = ill.get("source", "collimated")
    if source not in ("collimated", "point"):
        raise _err(path, "[illumination] source", f"must be 'collimated' or 'point'; got {source!r}")
    out["source"], out["distance_mm"], out["sample_radius_mm"] = source, None, None
    if source == "point":
        for key, name in (("distance_mm", "distance"), ("sample_radius_mm", "sample_radius")):
            if key not in ill:
                raise _err(
                    path, f"[illumination] {key}", "required for source = 'point' (a finite number > 0)"
                )
            out[key] = _declared(path, f"[illumination] {key}", PointSourceBRDF, name, ill[key])
        if out["sample_radius_mm"] > out["distance_mm"]:
            raise _err(path, "[illumination] sample_radius_mm", "must not exceed distance_mm")
    return out


def _coating(path, c):
    _unknown(path, "[coating] ", c, {"index", "roughness"})
    if "index" not in c:
        raise _err(path, "[coating] index", "required: a real index >= 1")
    out = {"index": _declared(path, "[coating] index", SubsurfaceFacetBRDF, "coating", c["index"])}
    if "roughness" in c:
        out["roughness"] = _distribution(path, "[coating.roughness] ", c["roughness"])
    return out


def _distribution(path, section, table):
    """The slope distribution a table names (``distribution = ...``) with its keys."""
    _unknown(path, section, table, {"distribution"} | {k for e in TABLE.values() for k in e.keys})
    kind = table.get("distribution")
    names = [n for n, e in TABLE.items() if e.kind == "distribution"]
    if kind not in names:
        raise _err(path, f"{section}distribution", f"must be one of {', '.join(names)}; got {kind!r}")
    return _built(path, section, kind, table)[0]


def _built(path, section, name, table, **given):
    """:func:`models.scene.table.build`, its errors naming the file and the key."""
    try:
        return build(name, table, **given)
    except KeyProblem as exc:
        raise _err(path, f"{section}{exc.key or name}", exc.message) from exc


def _index(path, key, value):
    """A TOML index (a number n, a pair [n, k], or "inf") as a Python one."""
    if value == "inf":
        return math.inf
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return complex(float(value), 0.0)
    if isinstance(value, list) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
        return complex(float(value[0]), float(value[1]))
    raise _err(path, key, f'must be a number n, a pair [n, k], or "inf"; got {value!r}')


def _substrate(path, s, data):
    _unknown(path, "[substrate] ", s, _SUBSTRATE_KEYS)
    kind = s.get("model", "facet")
    if kind not in SUBSTRATE_MODELS:
        raise _err(path, "[substrate] model", f"must be one of {', '.join(SUBSTRATE_MODELS)}; got {kind!r}")
    entry = TABLE[kind]
    for other in SUBSTRATE_MODELS:
        for k in TABLE[other].keys:
            if k in s and k not in entry.keys:
                raise _err(path, f"[substrate] {k}", f"only for model = {other!r}")
    if "index" not in s:
        raise _err(path, "[substrate] index", 'required: n, [n, k] or "inf"')
    index = _declared(
        path, "[substrate] index", entry.cls, "substrate", _index(path, "[substrate] index", s["index"])
    )
    if entry.alone:
        for table in ("coating", "volume"):
            if table in data:
                raise _err(
                    path,
                    f"[{table}]",
                    f"not with [substrate] model = {kind!r}: the model has no interface and carries its own "
                    "diffuse (rho_d) and volumetric (rho_v) terms",
                )
    if entry.slopes == "required" and "distribution" not in s:
        raise _err(
            path, "[substrate] distribution", f"required for model = {kind!r} (the specular facet term)"
        )
    out = {"index": index, "model": kind, "entry": entry, "slopes": None, "params": {}}
    if entry.slopes != "ignored" and "distribution" in s:
        dist = {k: v for k, v in s.items() if k not in entry.keys and k not in ("index", "model")}
        out["slopes"] = _distribution(path, "[substrate] ", dist)
    if entry.keys:
        given = {"slopes": out["slopes"]} if out["slopes"] is not None else {}
        keys = {k: v for k, v in s.items() if k in entry.keys}
        out["params"] = _built(path, "[substrate] ", kind, keys, substrate=index, **given)[1]
    return out


def _volume(path, v, coating):
    """``[volume]``: a pigment in the binder (seed 003).  The binder's index is the
    coating's, so a ``[coating]`` table is required."""
    _unknown(path, "[volume] ", v, set(VOLUME) | {"single", "interface"})
    if coating is None:
        raise _err(path, "[volume]", "needs a [coating] table: its index is the binder's index")
    out = {}
    for key, (cls, name) in VOLUME.items():
        out[key] = _declared(path, f"[volume] {key}", cls, name, v.get(key, VOLUME_DEFAULTS[key]))
    out["single"] = _flag(path, "[volume] single", v.get("single", True))
    interface = v.get("interface", "rough")
    if interface not in ("rough", "smooth"):
        raise _err(
            path,
            "[volume] interface",
            f"must be 'rough' (Monte Carlo under a rough coating) or 'smooth'; got {interface!r}",
        )
    out["interface"] = interface
    if out["rho"] == 0 and not out["single"]:
        raise _err(path, "[volume]", "declares no scattering: set rho > 0 or single = true")
    return out


def _detector(path, d):
    _unknown(path, "[detector] ", d, {"aperture_deg"})
    deg = _number(path, "[detector] aperture_deg", d.get("aperture_deg", 0.0))
    try:
        DetectorAperture.check_parameter("aperture", math.radians(deg))
    except ValueError as exc:
        raise _err(
            path, "[detector] aperture_deg", f"{exc} ({deg:g} deg in the file, converted to radians)"
        ) from exc
    return {"aperture_deg": deg}
