"""What a fit varies, how it weighs the data, and which data it ignores: the fit spec.

It comes from the scene file's ``[fit]`` table and/or the command line (the
command line replaces the scene's entries of the same kind).  Scene form::

    [fit]
    free = ["substrate.sigma:0.01:1:log", "coating.index:1.2:2", "substrate.index[0]:0.5:3"]

    [fit.noise]                 # a number: fixed; "low:high[:prior]": a free parameter;
    brdf = "0.005:1:log"        # "off": the term is not used even if the data have it
    eta_deg = 1.0               # principal-angle noise, degrees
    P = 0.02                    # degree-of-polarization noise
    P_C = "off"                 # degree of circular polarization: ignored

    [fit.mask]
    near_specular_deg = 2.0     # drop rows within 2 deg of the specular direction
    exclude = [{theta_r_deg = [53, 67], phi_r_deg = [180, 180]}]   # boxes, degrees, inclusive

Command line: ``--free substrate.sigma:0.01:1:log`` (repeatable), ``--noise
brdf=0.05``, ``--noise brdf:0.005:1:log`` or ``--noise eta_deg=off`` (a
BRDF-only fit of polarimetric data: ``--noise eta_deg=off --noise P=off
--noise P_C=off``), ``--near-specular-deg 2``,
``--exclude theta_r_deg=53:67,phi_r_deg=180:180``.

A free entry is ``KEY:LOW:HIGH[:PRIOR]`` with ``PRIOR`` ``uniform`` (default)
or ``log`` (log-uniform, ``LOW > 0``).  ``KEY`` is a dotted key of the scene
file (``substrate.index[1]`` is k of an ``[n, k]`` index) or, for the
coated-flake scenes, a short alias: ``sigma`` = ``substrate.sigma`` (``alpha`` =
``substrate.alpha`` for GGX slopes),
``coating`` = ``coating.index``, ``n`` = ``substrate.index[0]``, ``k`` =
``substrate.index[1]``.  Free noise terms are named ``noise.brdf``,
``noise.eta_deg``, ``noise.P``, ``noise.P_C``.

The sampler works in *sampling coordinates*: ``x`` for a uniform prior and
``ln x`` for a log-uniform one, where the prior is flat inside the bounds and
zero outside (bounds are enforced: ``log_prior`` is ``-inf`` there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from scatterbench.models.text import shown

__all__ = [
    "FreeParam",
    "FitSpec",
    "Values",
    "FitSpecError",
    "ALIASES",
    "NOISE_TERMS",
    "parse_free",
    "fitspec_from",
    "masked_rows",
]

ALIASES = {
    "sigma": "substrate.sigma",
    "alpha": "substrate.alpha",
    "coating": "coating.index",
    "n": "substrate.index[0]",
    "k": "substrate.index[1]",
    "coverage": "substrate.coverage",
}
#: noise term -> what it is (the brdf term is fractional: sigma of ln BRDF)
NOISE_TERMS = {
    "brdf": "fractional (speckle) noise of the BRDF: sigma of ln(BRDF)",
    "eta_deg": "principal-angle noise, degrees",
    "P": "degree-of-polarization noise",
    "P_C": "degree-of-circular-polarization noise",
}
_PRIORS = ("uniform", "log")
_MASK_AXES = ("theta_i_deg", "theta_r_deg", "phi_r_deg")


class FitSpecError(ValueError):
    """A fit-spec problem; the message names the entry and the allowed values."""


@dataclass(frozen=True)
class FreeParam:
    key: str  # dotted scene key or noise.<term>
    low: float
    high: float
    prior: str = "uniform"

    @property
    def is_noise(self) -> bool:
        return self.key.startswith("noise.")

    def to_u(self, x):
        return np.log(x) if self.prior == "log" else np.asarray(x, dtype=float)

    def from_u(self, u):
        return np.exp(u) if self.prior == "log" else np.asarray(u, dtype=float)

    @property
    def u_bounds(self):
        return (math.log(self.low), math.log(self.high)) if self.prior == "log" else (self.low, self.high)

    def as_text(self):
        return f"{self.key}:{self.low:g}:{self.high:g}:{self.prior}"


@dataclass(frozen=True)
class Values:
    """Physical values of sampling positions (:meth:`FitSpec.values`): ``scene``, the scene's
    free keys; ``noise``, every noise level by term (fixed or free)."""

    scene: dict
    noise: dict


@dataclass(frozen=True)
class FitSpec:
    free: tuple  # of FreeParam, scene parameters first, then noise terms
    noise: dict = field(default_factory=dict)  # fixed noise values by term
    near_specular_deg: float = 0.0
    exclude: tuple = ()  # of {axis: (lo, hi)}
    off: tuple = ()  # polarization terms not used, even where the data have them

    @property
    def names(self):
        return [p.key for p in self.free]

    def u_bounds(self):
        return np.array([p.u_bounds for p in self.free])

    def log_prior(self, u):
        """Flat in sampling coordinates inside the bounds (the prior density of the
        declared uniform/log-uniform priors, up to a constant); ``-inf`` outside or where a
        coordinate is not finite.  Vectorized: one position ``(k,)`` gives a float,
        positions ``(W, k)`` a ``(W,)`` array (the likelihood's batch of walkers)."""
        b = self.u_bounds()
        u = np.asarray(u, dtype=float)
        inside = np.all(np.isfinite(u) & (u >= b[:, 0]) & (u <= b[:, 1]), axis=-1)
        out = np.where(inside, 0.0, -math.inf)
        return float(out) if out.ndim == 0 else out

    def values(self, u) -> Values:
        """The physical values of sampling positions, once: ``u`` ``(k,)`` gives floats,
        positions ``(W, k)`` give ``(W, 1)`` arrays (a model set over the walkers), split into
        the scene's free keys and the noise levels (the fixed ones included)."""
        u = np.asarray(u, dtype=float)
        scene, noise = {}, dict(self.noise)
        for i, p in enumerate(self.free):
            x = p.from_u(u[..., i])
            x = float(x) if u.ndim == 1 else x[:, None]
            if p.is_noise:
                noise[p.key[6:]] = x
            else:
                scene[p.key] = x
        return Values(scene, noise)

    def physical(self, u) -> dict:
        """One position's physical values by free key (``noise.<term>`` for noise levels):
        what a report shows."""
        return {p.key: float(p.from_u(v)) for p, v in zip(self.free, u, strict=True)}

    def mask(self, data) -> np.ndarray:
        """Boolean array: True for the rows the fit uses."""
        keep = np.ones(len(data), dtype=bool)
        if self.near_specular_deg > 0:
            keep &= (
                np.degrees(specular_distance(data.theta_i, data.theta_r, data.phi_r)) > self.near_specular_deg
            )
        deg = {
            "theta_i_deg": np.degrees(data.theta_i),
            "theta_r_deg": np.degrees(data.theta_r),
            "phi_r_deg": np.degrees(data.phi_r),
        }
        for box in self.exclude:
            inside = np.ones(len(data), dtype=bool)
            for axis, (lo, hi) in box.items():
                v = deg[axis]
                if axis == "phi_r_deg":
                    v = lo + np.mod(v - lo + 1e-9, 360.0) - 1e-9  # the azimuth's turn that starts at lo
                inside &= (v >= lo - 1e-9) & (v <= hi + 1e-9)
            keep &= ~inside
        return keep

    def kept(self, data) -> np.ndarray:
        """:meth:`mask`, or :class:`FitSpecError` when it keeps no row of ``data``."""
        keep = self.mask(data)
        if not keep.any():
            raise FitSpecError(f"{data.path}: mask: every data row is masked out; no row is left")
        return keep

    def describe(self) -> str:
        lines = ["free parameters (prior, bounds):"]
        lines += [f"  {p.key:<22} {p.prior:<8} [{p.low:g}, {p.high:g}]" for p in self.free]
        if self.noise:
            lines.append("fixed noise: " + ", ".join(f"{k}={v:g}" for k, v in self.noise.items()))
        if self.off:
            lines.append("terms off: " + ", ".join(self.off))
        if self.near_specular_deg or self.exclude:
            lines.append(f"mask: near_specular_deg={self.near_specular_deg:g}, exclude={list(self.exclude)}")
        return "\n".join(lines)

    def as_dict(self):
        return {
            "free": [p.as_text() for p in self.free],
            "noise": dict(self.noise),
            "off": list(self.off),
            "near_specular_deg": self.near_specular_deg,
            "exclude": [{k: list(v) for k, v in b.items()} for b in self.exclude],
        }


def specular_distance(ti, tr, pr):
    """Angle (radians) between the scattering direction and the specular direction."""
    ti, tr, pr = np.broadcast_arrays(np.asarray(ti, float), np.asarray(tr, float), np.asarray(pr, float))
    c = np.cos(tr) * np.cos(ti) + np.sin(tr) * np.sin(ti) * np.cos(pr)
    return np.arccos(np.clip(c, -1.0, 1.0))


def _num(where, text):
    """A number given as a number or as text (``"0.5"`` on the command line); not a bool."""
    if isinstance(text, bool) or not isinstance(text, (int, float, str)):
        raise FitSpecError(f"{where}: {shown(text)} is not a number")
    try:
        v = float(text)
    except (ValueError, OverflowError):
        raise FitSpecError(f"{where}: {shown(text)} is not a number") from None
    if not math.isfinite(v):
        raise FitSpecError(f"{where}: {shown(text)} is not a finite number")
    return v


def parse_free(text, where="--free") -> FreeParam:
    """``KEY:LOW:HIGH[:PRIOR]`` -> :class:`FreeParam` (aliases resolved, bounds checked)."""
    if not isinstance(text, str):
        raise FitSpecError(f"{where}: expected 'KEY:LOW:HIGH[:uniform|log]'; got {text!r}")
    parts = text.split(":")
    if len(parts) not in (3, 4):
        raise FitSpecError(f"{where}: expected 'KEY:LOW:HIGH[:uniform|log]'; got {text!r}")
    key = ALIASES.get(parts[0].strip(), parts[0].strip())
    low, high = _num(f"{where} {key} low", parts[1]), _num(f"{where} {key} high", parts[2])
    prior = parts[3].strip() if len(parts) == 4 else "uniform"
    return _free(where, key, low, high, prior)


def _free(where, key, low, high, prior):
    if prior not in _PRIORS:
        raise FitSpecError(f"{where} {key}: prior must be 'uniform' or 'log'; got {prior!r}")
    if not low < high:
        raise FitSpecError(f"{where} {key}: needs low < high; got [{low:g}, {high:g}]")
    if prior == "log" and low <= 0:
        raise FitSpecError(f"{where} {key}: a log-uniform prior needs low > 0; got {low:g}")
    if key.startswith("noise."):
        term = key[6:]
        if term not in NOISE_TERMS:
            raise FitSpecError(
                f"{where} {key}: unknown noise term; allowed: noise.{', noise.'.join(NOISE_TERMS)}"
            )
        if low < 0:
            raise FitSpecError(f"{where} {key}: a noise level must be >= 0; got low {low:g}")
    return FreeParam(key, float(low), float(high), prior)


def _noise_entry(where, term, value):
    if term not in NOISE_TERMS:
        raise FitSpecError(f"{where}: unknown noise term {term!r}; allowed: {', '.join(NOISE_TERMS)}")
    if isinstance(value, str) and value.strip() == "off":
        if term == "brdf":
            raise FitSpecError(f"{where} brdf: the BRDF term cannot be off (every fit uses it)")
        return "off"
    if isinstance(value, str) and ":" in value:
        return parse_free(f"noise.{term}:{value}", where)
    v = _num(f"{where} {term}", value)
    if v < 0:
        raise FitSpecError(f"{where} {term}: a noise level must be >= 0; got {v:g}")
    return v


def _exclude_box(where, box):
    if not isinstance(box, dict) or not box:
        raise FitSpecError(
            f"{where}: each exclude entry is a table {{axis = [lo, hi]}} with axes {_MASK_AXES}"
        )
    out = {}
    for axis, rng in box.items():
        if axis not in _MASK_AXES:
            raise FitSpecError(f"{where}: unknown axis {axis!r}; allowed: {', '.join(_MASK_AXES)}")
        if not (isinstance(rng, (list, tuple)) and len(rng) == 2):
            raise FitSpecError(f"{where} {axis}: expected [lo, hi] in degrees; got {rng!r}")
        lo, hi = _num(f"{where} {axis}", rng[0]), _num(f"{where} {axis}", rng[1])
        if lo > hi:
            raise FitSpecError(f"{where} {axis}: needs lo <= hi; got [{lo:g}, {hi:g}]")
        out[axis] = (lo, hi)
    return out


def parse_exclude(text) -> dict:
    """``theta_r_deg=53:67,phi_r_deg=180:180`` -> box."""
    box = {}
    for part in text.split(","):
        axis, _, rng = part.partition("=")
        lo, _, hi = rng.partition(":")
        box[axis.strip()] = [lo, hi]
    return _exclude_box("--exclude", box)


def _free_entries(where, table, free):
    """The free scene parameters: the command line's ``free`` entries, else the table's."""
    if free:
        return [parse_free(t) for t in free]
    entries = table.get("free", [])
    if not isinstance(entries, list):
        raise FitSpecError(f"{where} free: expected a list of 'KEY:LOW:HIGH[:PRIOR]' strings or tables")
    return [
        _free_table(f"{where} free", e) if isinstance(e, dict) else parse_free(e, f"{where} free")
        for e in entries
    ]


def _free_table(where, e):
    """A free entry given as a table ``{key, low, high[, prior]}``."""
    missing = {"key", "low", "high"} - set(e)
    if missing:
        raise FitSpecError(f"{where}: table entry {shown(e)} lacks {sorted(missing)}")
    extra = set(e) - {"key", "low", "high", "prior"}
    if extra:
        raise FitSpecError(
            f"{where}: unknown key(s) {sorted(extra)} in {shown(e)}; allowed: key, low, high, prior"
        )
    if not isinstance(e["key"], str):
        raise FitSpecError(f"{where}: key must be a dotted scene key (a string); got {shown(e['key'])}")
    if not isinstance(e.get("prior", "uniform"), str):
        raise FitSpecError(f"{where} {e['key']}: prior must be 'uniform' or 'log'; got {shown(e['prior'])}")
    key = ALIASES.get(e["key"], e["key"])
    low, high = _num(f"{where} {key} low", e["low"]), _num(f"{where} {key} high", e["high"])
    return _free(where, key, low, high, e.get("prior", "uniform"))


def _noise_entries(where, table, noise):
    """``(free noise params, fixed levels by term, terms off)`` from the table's ``[fit.noise]``
    with the command line's ``--noise`` entries replacing the table's for their term."""
    noise_tab = table.get("noise", {})
    if not isinstance(noise_tab, dict):
        raise FitSpecError(f"{where} noise: expected a table")
    items = list(noise_tab.items())
    for text in noise or []:
        if "=" in text:
            term, _, val = text.partition("=")
        elif ":" in text:
            term, _, val = text.partition(":")
        else:
            raise FitSpecError(f"--noise: expected TERM=VALUE or TERM:LOW:HIGH[:PRIOR]; got {text!r}")
        items = [(k, v) for k, v in items if k != term.strip()]
        items.append((term.strip(), val))
    params, fixed, off = [], {}, []
    for term, value in items:
        e = _noise_entry(f"{where} noise" if not noise else "--noise", term, value)
        if e == "off":
            off.append(term)
        elif isinstance(e, FreeParam):
            params.append(e)
        else:
            fixed[term] = e
    return params, fixed, off


def _check_free(scene, where, params, noise_fixed):
    """No parameter twice, at least one scene parameter, every key in the scene and every
    bound a valid scene."""
    keys = [p.key for p in params]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        raise FitSpecError(f"free parameter(s) given twice: {sorted(dup)}")
    if not [p for p in params if not p.is_noise]:
        raise FitSpecError(
            f"{where}: no free scene parameter; give --free KEY:LOW:HIGH[:PRIOR] (e.g. substrate.sigma:0.01:1:log)"
        )
    for p in params:
        if p.key.startswith("noise.") and p.key[6:] in noise_fixed:
            raise FitSpecError(f"{p.key}: both fixed and free")
    for p in (p for p in params if not p.is_noise):
        try:
            cur = scene.get_value(p.key)
        except ValueError as exc:
            raise FitSpecError(f"free parameter {p.key}: {exc}") from exc
        if isinstance(cur, list) and "[" not in p.key:
            raise FitSpecError(f"free parameter {p.key}: is a pair [n, k]; free {p.key}[0] and/or {p.key}[1]")
        for bound in (p.low, p.high):
            try:
                scene.with_values({p.key: bound}).build()
            except ValueError as exc:
                raise FitSpecError(
                    f"free parameter {p.key}: bound {bound:g} gives an invalid scene: {exc}"
                ) from exc


def _mask_entries(where, table, near_specular_deg, exclude):
    """``(near_specular_deg, exclude boxes)``: the command line's where given, else the table's."""
    mask = table.get("mask", {})
    if not isinstance(mask, dict):
        raise FitSpecError(f"{where} mask: expected a table")
    bad = set(mask) - {"near_specular_deg", "exclude"}
    if bad:
        raise FitSpecError(f"{where} mask: unknown key(s) {sorted(bad)}; allowed: near_specular_deg, exclude")
    ns = mask.get("near_specular_deg", 0.0) if near_specular_deg is None else near_specular_deg
    ns = _num(f"{where} mask near_specular_deg", ns)
    if not 0 <= ns <= 180:
        raise FitSpecError(f"near_specular_deg must be in [0, 180]; got {ns:g}")
    table_boxes = mask.get("exclude", [])
    if not isinstance(table_boxes, list):
        raise FitSpecError(
            f"{where} mask exclude: expected a list of tables {{axis = [lo, hi]}}; got {shown(table_boxes)}"
        )
    boxes = [_exclude_box(f"{where} mask exclude", b) for b in table_boxes]
    if exclude:
        boxes = [parse_exclude(t) for t in exclude]
    return ns, tuple(boxes)


def fitspec_from(scene, free=None, noise=None, near_specular_deg=None, exclude=None) -> FitSpec:
    """Combine the scene's ``[fit]`` table with command-line entries and validate
    them against the scene (every key exists; the bounds give valid scenes).

    Parameters
    ----------
    scene : models.scene.Scene
        Its ``[fit]`` table gives the defaults.
    free : list of str, optional
        ``KEY:LOW:HIGH[:PRIOR]`` entries replacing the table's free list.
    noise : list of str, optional
        ``TERM=VALUE``, ``TERM=off`` or ``TERM:LOW:HIGH[:PRIOR]`` entries replacing
        the table's for their term.
    near_specular_deg : float, optional
        Mask rows within this angle of specular, in [0, 180] (replaces the table's).
    exclude : list of str, optional
        ``AXIS=LO:HI[,AXIS=LO:HI]`` boxes replacing the table's.

    Returns
    -------
    FitSpec

    Raises
    ------
    FitSpecError
        An entry out of range or not in the scene; the message names it.
    """
    table = dict(scene.fit or {})
    where = f"{scene.path}: [fit]"
    # [fit.mueller] is read by fits to Mueller-matrix data (fitting.mueller_spec)
    unknown = set(table) - {"free", "noise", "mask", "mueller"}
    if unknown:
        raise FitSpecError(f"{where}: unknown key(s) {sorted(unknown)}; allowed: free, noise, mask, mueller")
    params = _free_entries(where, table, free)
    noise_params, noise_fixed, off = _noise_entries(where, table, noise)
    params += noise_params
    _check_free(scene, where, params, noise_fixed)
    params = [p for p in params if not p.is_noise] + [p for p in params if p.is_noise]
    ns, boxes = _mask_entries(where, table, near_specular_deg, exclude)
    return FitSpec(free=tuple(params), noise=noise_fixed, near_specular_deg=ns, exclude=boxes, off=tuple(off))


def masked_rows(data, near_specular_deg=None, exclude=None):
    """The rows of ``data`` a mask keeps (``--near-specular-deg``, ``--exclude``, as in
    :func:`fitspec_from`); :class:`FitSpecError` when it keeps none."""
    ns, boxes = _mask_entries("--", {}, near_specular_deg, exclude)
    return data.subset(FitSpec((), {}, ns, boxes).kept(data))
