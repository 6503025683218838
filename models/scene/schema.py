"""Scene TOML schema: the tables and keys a scene file may hold, validated into plain data.

The scene checks what is its own: the tables and keys that exist, which ones are
required, and combinations (a ``[volume]`` needs a ``[coating]``, Maxwell-Beard stands
alone).  Values that a model takes are validated by that model's declared parameters
(:mod:`scatterbench.models.params`, through :mod:`scatterbench.models.scene.table`); every error is a
:class:`SceneError` naming the file, the key and the allowed values.
"""

from __future__ import annotations

import math
import re

from ..aperture import DetectorAperture
from ..facet import FacetBRDF
from ..point_source import PointSourceBRDF
from ..polarization import stokes
from ..slopes import GaussianSlopes
from ..subsurface_facet import SubsurfaceFacetBRDF
from ..text import is_number, shown
from ..thin_film import Films, FilmStack
from .assembly import monte_carlo_volume
from .table import SUBSTRATE_MODELS, TABLE, VOLUME, VOLUME_DEFAULTS, KeyProblem, build

__all__ = [
    "SceneError",
    "parse",
    "check_structure",
    "MAX_DEPTH",
]

#: how deeply tables and arrays may nest in a scene file (the deepest schema entry,
#: ``[fit.mask] exclude = [{theta_r_deg = [lo, hi]}]``, is 5 levels)
MAX_DEPTH = 16

_TOP = {"name", "description", "illumination", "coating", "substrate", "volume", "detector", "fit"}
_ILLUM = {"theta_i_deg", "polarization", "wavelength_nm", "source", "distance_mm", "sample_radius_mm"}
_SUBSTRATE_KEYS = {"index", "distribution", "model", "film"} | {k for e in TABLE.values() for k in e.keys}
#: the keys of the slope distributions (sigma, sigma_x, ..., coverage)
_SLOPE_KEYS = {k for e in TABLE.values() if e.kind == "distribution" for k in e.keys}


class SceneError(ValueError):
    """A scene file problem; the message names the file, the key and the allowed values."""


def _key_path(keys):
    """``[substrate] sigma``, ``[fit] free[0].low``: a value's place, as the errors name it."""
    if not keys:
        return "scene"
    head, rest = keys[0], keys[1:]
    if not rest:
        return str(head)
    tail = "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in rest)
    return f"[{head}] {tail.lstrip('.')}"


def check_structure(data, path: str) -> None:
    """Raise :class:`SceneError` for what no key of a scene can hold: tables or arrays nested
    deeper than :data:`MAX_DEPTH`, integers no float can hold (the values are numbers of
    double precision), control characters in keys.  Iterative: a pathological file cannot
    exhaust the stack here."""
    stack = [((), data)]
    while stack:
        keys, v = stack.pop()
        if len(keys) > MAX_DEPTH:
            raise _err(path, _key_path(keys[:2]), f"nested more than {MAX_DEPTH} levels deep")
        if isinstance(v, dict):
            for k, x in v.items():
                if not isinstance(k, str) or not k.isprintable():
                    raise _err(
                        path, _key_path(keys) + f" {k!r}", "a key must be a string of printable characters"
                    )
                stack.append((keys + (k,), x))
        elif isinstance(v, list):
            stack.extend((keys + (i,), x) for i, x in enumerate(v))
        elif isinstance(v, int) and not isinstance(v, bool) and not is_number(v):
            raise _err(
                path, _key_path(keys), f"{str(v)[:20]}... ({len(str(v))} digits) is too large a number"
            )


def parse(data: dict, path: str) -> dict:
    """The validated fields of :class:`scatterbench.models.scene.Scene` from the dict a TOML file parses to."""
    _unknown(path, "", data, _TOP)
    name = data.get("name")
    if not isinstance(name, str) or not name.strip() or not name.isprintable():
        raise _err(
            path,
            "name",
            f"a non-empty, one-line string of printable characters is required; got {shown(name)}",
        )
    if "fit" in data and not isinstance(data["fit"], dict):
        raise _err(path, "[fit]", f"must be a table (free, noise, mask); got {shown(data['fit'])}")
    out = {"name": name, **_illumination(path, data.get("illumination"))}
    out["coating"] = _coating(path, data["coating"], out["wavelength_nm"]) if "coating" in data else None
    out["substrate"] = (
        _substrate(path, data["substrate"], data, out["wavelength_nm"]) if "substrate" in data else None
    )
    out["volume"] = _volume(path, data["volume"], out["coating"]) if "volume" in data else None
    _coating_films_apply(path, out)
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
    if not is_number(value):
        raise _err(path, key, f"must be a finite number; got {shown(value)}")
    if low is not None and (value < low or (low_open and value == low)):
        raise _err(path, key, f"must be {'>' if low_open else '>='} {low:g}; got {shown(value)}")
    if high is not None and value > high:
        raise _err(path, key, f"must be <= {high:g}; got {shown(value)}")
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
    for key in ("distance_mm", "sample_radius_mm"):
        if source == "collimated" and key in ill:
            raise _err(
                path, f"[illumination] {key}", "only for source = 'point' (a collimated beam has none)"
            )
    return out


def _coating(path, c, wavelength_nm):
    _unknown(path, "[coating] ", c, {"index", "roughness", "film"})
    if "index" not in c:
        raise _err(path, "[coating] index", "required: a real index >= 1")
    out = {"index": _declared(path, "[coating] index", SubsurfaceFacetBRDF, "coating", c["index"])}
    out["films"] = None
    if "film" in c:
        layers = _film_layers(path, "[coating.film]", c["film"], wavelength_nm)
        out["films"] = _film_built(path, "[coating.film]", Films, layers=layers, wavelength_nm=wavelength_nm)
    if "roughness" in c:
        rough = c["roughness"]
        if not isinstance(rough, dict):
            raise _err(path, "[coating.roughness]", "must be a table")
        table = {k: v for k, v in rough.items() if k != "shadowing"}
        out["roughness"] = _distribution(path, "[coating.roughness] ", table)
        out["shadowing"] = "none"
        if "shadowing" in rough:
            key = "[coating.roughness] shadowing"
            out["shadowing"] = _declared(path, key, FacetBRDF, "shadowing", rough["shadowing"])
            try:  # the choice with these slopes (Smith needs isotropic or elliptical ones)
                FacetBRDF(slopes=out["roughness"], substrate=out["index"], shadowing=out["shadowing"])
            except ValueError as exc:
                raise _err(path, key, str(exc)) from exc
    return out


def _distribution(path, section, table):
    """The slope distribution a table names (``distribution = ...``) with its keys."""
    _unknown(path, section, table, {"distribution"} | _SLOPE_KEYS)
    kind = table.get("distribution")
    names = [n for n, e in TABLE.items() if e.kind == "distribution"]
    if kind not in names:
        raise _err(path, f"{section}distribution", f"must be one of {', '.join(names)}; got {shown(kind)}")
    for k in table:
        if k != "distribution" and k not in TABLE[kind].keys:
            raise _err(
                path,
                f"{section}{k}",
                f"not a key of distribution {kind!r} (its keys: {', '.join(TABLE[kind].keys)})",
            )
    return _built(path, section, kind, table)[0]


def _built(path, section, name, table, **given):
    """:func:`scatterbench.models.scene.table.build`, its errors naming the file and the key."""
    try:
        return build(name, table, **given)
    except KeyProblem as exc:
        raise _err(path, f"{section}{exc.key or name}", exc.message) from exc


def _index(path, key, value):
    """A TOML index (a number n, a pair [n, k], or "inf") as a Python one."""

    def real(v):
        return isinstance(v, (int, float)) and not isinstance(v, bool)

    if value == "inf":
        return math.inf
    if real(value):
        return complex(float(value), 0.0)
    if isinstance(value, list) and len(value) == 2 and all(real(v) for v in value):
        return complex(float(value[0]), float(value[1]))
    raise _err(path, key, f'must be a number n, a pair [n, k], or "inf"; got {shown(value)}')


def _substrate(path, s, data, wavelength_nm):
    _unknown(path, "[substrate] ", s, _SUBSTRATE_KEYS)
    kind = s.get("model", "facet")
    if kind not in SUBSTRATE_MODELS:
        raise _err(path, "[substrate] model", f"must be one of {', '.join(SUBSTRATE_MODELS)}; got {kind!r}")
    entry = TABLE[kind]
    for k in sorted(set(s) - set(entry.keys)):
        owners = [repr(m) for m in SUBSTRATE_MODELS if k in TABLE[m].keys]
        if owners:
            raise _err(path, f"[substrate] {k}", f"only for model = {' or '.join(owners)}")
    if "film" in s and kind != "facet":
        raise _err(path, "[substrate.film]", f"only for model = 'facet' (films on facets); not for {kind!r}")
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
    _slope_keys_apply(path, s, kind, entry)
    if "film" in s:
        index = _film(path, s["film"], index, wavelength_nm)
    out = {"index": index, "model": kind, "entry": entry, "slopes": None, "params": {}}
    if entry.slopes != "ignored" and "distribution" in s:
        dist = {k: v for k, v in s.items() if k not in entry.keys and k not in ("index", "model", "film")}
        out["slopes"] = _distribution(path, "[substrate] ", dist)
    if entry.keys:
        given = {"slopes": out["slopes"]} if out["slopes"] is not None else {}
        keys = {k: v for k, v in s.items() if k in entry.keys}
        out["params"] = _built(path, "[substrate] ", kind, keys, substrate=index, **given)[1]
    return out


def _film(path, film, substrate, wavelength_nm):
    """``[substrate.film]``: thin films on the substrate/flakes (:class:`scatterbench.models.FilmStack`)."""
    layers = _film_layers(path, "[substrate.film]", film, wavelength_nm)
    return _film_built(
        path, "[substrate.film]", FilmStack, layers=layers, substrate=substrate, wavelength_nm=wavelength_nm
    )


def _film_layers(path, section, film, wavelength_nm):
    """The layers of a film table (``[substrate.film]``, ``[coating.film]``): ``layers =
    [{index = [n, k], thickness_nm = d}, ...]`` from the incident side down, at
    ``[illumination] wavelength_nm``, as ``((index, thickness_nm), ...)`` (values unchecked)."""
    _unknown(path, f"{section} ", film, {"layers"})
    if wavelength_nm is None:
        raise _err(
            path,
            "[illumination] wavelength_nm",
            f"required with {section}: the films' phase thicknesses depend on the wavelength",
        )
    layers = film.get("layers")
    if not isinstance(layers, list) or not layers:
        raise _err(
            path,
            f"{section} layers",
            f"required: a non-empty array of tables {{index = [n, k], thickness_nm = d}}; got {shown(layers)}",
        )
    out = []
    for j, layer in enumerate(layers):
        key = f"{section} layers[{j}]"
        if not isinstance(layer, dict):
            raise _err(path, key, f"must be a table {{index = [n, k], thickness_nm = d}}; got {shown(layer)}")
        _unknown(path, f"{key}.", layer, {"index", "thickness_nm"})
        for k, what in (("index", "n or [n, k] (finite)"), ("thickness_nm", "a number >= 0")):
            if k not in layer:
                raise _err(path, f"{key}.{k}", f"required: {what}")
        out.append((_index(path, f"{key}.index", layer["index"]), layer["thickness_nm"]))
    return tuple(out)


def _film_built(path, section, cls, **kw):
    """``cls(**kw)`` (:class:`scatterbench.models.FilmStack` or :class:`scatterbench.models.Films`), which validates the
    values; its message names ``layers[j] index / thickness_nm``, the error the file's key."""
    try:
        return cls(**kw)
    except ValueError as exc:
        m = re.match(r"layers\[(\d+)\] (index|thickness_nm)", str(exc))
        key = f"{section} layers[{m[1]}].{m[2]}" if m else section
        raise _err(path, key, str(exc)) from exc


def _coating_films_apply(path, out):
    """``[coating.film]`` only where a model takes films on the coating's top surface: facets
    under it (:class:`scatterbench.models.SubsurfaceFacetBRDF`), a volume under a smooth interface
    (:class:`scatterbench.models.SingleScatterBRDF`, :class:`scatterbench.models.DiffuseSubsurfaceBRDF`) and the rough
    top surface's own facet reflection; not seed 001's varnish model, nor the Monte Carlo
    model under a rough interface."""
    coating, sub, vol = out["coating"], out["substrate"], out["volume"]
    if coating is None or coating["films"] is None:
        return
    if sub is not None and sub["model"] != "facet":
        raise _err(
            path,
            "[coating.film]",
            f"not with [substrate] model = {sub['model']!r}: its varnish model takes no films "
            "(films on the coating go with model = 'facet' or a [volume])",
        )
    if monte_carlo_volume(coating, vol):
        raise _err(
            path,
            "[coating.film]",
            "not with a [volume] under the rough coating (interface = 'rough'): its Monte Carlo model "
            "has no films; use interface = 'smooth' or omit [coating.film]",
        )


def _slope_keys_apply(path, s, kind, entry):
    """A slope key (or ``distribution``) in ``[substrate]`` only where it sets the slopes."""
    if kind == "facet" and "shadowing" in s and "distribution" not in s:
        raise _err(
            path,
            "[substrate] shadowing",
            "only with a slope distribution (distribution = ...); a flat substrate casts no shadows",
        )
    for k in sorted(set(s) & (_SLOPE_KEYS | {"distribution"})):
        if entry.slopes == "ignored":
            raise _err(
                path,
                f"[substrate] {k}",
                f"not for model = {kind!r}: its roughness is its own ({', '.join(entry.required[0])})",
            )
        if k != "distribution" and "distribution" not in s:
            raise _err(
                path,
                f"[substrate] {k}",
                "only with a slope distribution (distribution = ...); without one the substrate is flat",
            )


def _volume(path, v, coating):
    """``[volume]``: a pigment in the binder (seed 003).  The binder's index is the
    coating's, so a ``[coating]`` table is required."""
    _unknown(path, "[volume] ", v, set(VOLUME) | {"single", "interface", "method"})
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
    monte_carlo = monte_carlo_volume(coating, out)
    if monte_carlo and coating.get("shadowing", "none") != "none":
        raise _err(
            path,
            "[coating.roughness] shadowing",
            "not with a [volume] under the rough coating (interface = 'rough'): its Monte Carlo model "
            "carries the rough surface's reflection and has no shadowing; use interface = 'smooth' or omit it",
        )
    out["method"] = _volume_method(path, v, coating, out, monte_carlo)
    for key in ("pairs", "seed"):
        if key in v and (not monte_carlo or out["method"] == "quadrature"):
            raise _err(
                path,
                f"[volume] {key}",
                "only for the Monte Carlo model (a [coating.roughness] with interface = 'rough'); "
                "this volume is evaluated in closed form",
            )
    if "single_weight" in v and not out["single"]:
        raise _err(
            path, "[volume] single_weight", "only with single = true (the weight of single scattering)"
        )
    return out


def _volume_method(path, v, coating, out, monte_carlo):
    """``[volume] method``: under the rough coating, ``"monte-carlo"`` (default: seed 003 Sec.
    2.5, :class:`scatterbench.models.RoughDiffuseBRDF`) or ``"quadrature"`` (its totally diffuse
    term's expectation, :class:`scatterbench.models.RoughSubsurfaceBRDF`: no single scattering,
    Gaussian slopes)."""
    method = v.get("method", "monte-carlo")
    if method not in ("monte-carlo", "quadrature"):
        raise _err(path, "[volume] method", f"must be 'monte-carlo' or 'quadrature'; got {method!r}")
    if method == "monte-carlo":
        return method
    if not monte_carlo:
        raise _err(
            path,
            "[volume] method",
            "only under a rough coating (a [coating.roughness] with interface = 'rough')",
        )
    if out["single"]:
        raise _err(
            path,
            "[volume] method",
            "'quadrature' computes the totally diffuse term alone: set single = false "
            "(single scattering under a rough interface is the Monte Carlo model's)",
        )
    if not isinstance(coating["roughness"], GaussianSlopes):
        raise _err(
            path,
            "[volume] method",
            "'quadrature' integrates Gaussian slopes: [coating.roughness] distribution = 'gaussian'",
        )
    return method


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
