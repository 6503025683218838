"""Scenes: a sample and a measurement described once, in TOML, built into the
cheapest model that represents them.

``load(path)`` reads and validates a scene file (standard-library ``tomllib``);
every error names the file, the key and the allowed values.  ``Scene.build()``
returns the composite model holding only the mechanisms the scene declares,
and ``Scene.mechanisms()`` says which ones and why.

Schema (angles in degrees in files, as everywhere outside the Python API)::

    name = "Aluminium flakes under a clear coat"

    [illumination]
    theta_i_deg = 60.0
    polarization = "linear:45"     # unpolarized | s | p | +45 | -45 | left | right | linear:<deg> | [I, Q, U, V]
    wavelength_nm = 632.8
    source = "collimated"          # collimated | point
    distance_mm = 500.0            # point source: its height above the sample plane (seed 001's d)
    sample_radius_mm = 10.0        # point source: illuminated radius

    [coating]                      # optional clear layer over the substrate/flakes
    index = 1.5
    [coating.roughness]            # optional: rough top surface (its own facet reflection)
    distribution = "gaussian"
    sigma = 0.02

    [substrate]                    # the flakes or the substrate under the coating
    index = [1.37, 7.62]           # [n, k], a number, or "inf" (perfect conductor)
    distribution = "exponential"   # omit for a flat (specular) substrate
    sigma = 0.1
    coverage = 1.0

    [volume]                       # optional volume scatterer (pigment) in the coating
    ...

    # or, instead of the facet substrate: an empirical model with no interface
    [substrate]
    model = "maxwell-beard"        # facet (default) | cook-torrance | maxwell-beard
    index = 1.5                    # Fresnel reflectance of the specular facets
    distribution = "gaussian"      # facet slopes of the specular term
    sigma = 0.05
    rho_d = 0.02                   # Lambertian BRDF, 1/sr
    rho_v = 0.01                   # volumetric coefficient, 1/sr: 2 rho_v / (cos ti + cos tr)
    tau_deg = 15.0                 # shadowing/obscuration parameters (defaults: the model's)
    omega_deg = 40.0
    polarized = true               # facet Mueller matrix on the specular term (false: published scalar form)

    [detector]
    aperture_deg = 0.7
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field

from . import slopes as _slopes
from .base import Model
from .facet import FacetBRDF
from .polarization import stokes
from .subsurface_facet import SubsurfaceFacetBRDF

__all__ = ["Scene", "SceneError", "Mechanism", "load", "loads", "from_dict", "DISTRIBUTIONS"]

#: distribution names in scene files and the classes (and their parameters) they map to
DISTRIBUTIONS = {
    "exponential": (_slopes.ExponentialSlopes, ("sigma", "coverage")),
    "gaussian": (_slopes.GaussianSlopes, ("sigma", "coverage")),
    "anisotropic-exponential": (
        _slopes.AnisotropicExponentialSlopes,
        ("sigma_x", "sigma_y", "rotation_deg", "coverage"),
    ),
    "anisotropic-gaussian": (
        _slopes.AnisotropicGaussianSlopes,
        ("sigma_x", "sigma_y", "rotation_deg", "coverage"),
    ),
    "gaussian-angle": (_slopes.GaussianAngles, ("sigma_deg", "coverage")),
    "exponential-angle": (_slopes.ExponentialAngles, ("sigma_deg", "coverage")),
}

_TOP = {"name", "description", "illumination", "coating", "substrate", "volume", "detector", "fit"}
_ILLUM = {"theta_i_deg", "polarization", "wavelength_nm", "source", "distance_mm", "sample_radius_mm"}


class SceneError(ValueError):
    """A scene file problem; the message names the file, the key and the allowed values."""


@dataclass(frozen=True)
class Mechanism:
    name: str
    model: Model
    why: str


@dataclass(frozen=True)
class Scene:
    name: str
    path: str
    theta_i: float  # radians
    polarization: tuple
    wavelength_nm: float | None
    source: str
    distance_mm: float | None
    sample_radius_mm: float | None
    coating: dict | None
    substrate: dict | None
    volume: dict | None
    detector: dict | None
    fit: dict | None = None
    raw: dict = field(default_factory=dict, repr=False, compare=False)

    def get_value(self, key: str):
        """The raw value at a dotted key of the scene file, e.g. ``substrate.sigma``,
        ``coating.index``, ``substrate.index[1]`` (k of an [n, k] index)."""
        node, last, idx = self._locate(copy.deepcopy(self.raw), key)
        v = node[last]
        return v[idx] if idx is not None else v

    def with_values(self, values: dict) -> Scene:
        """A new, re-validated scene with the given dotted keys set (for fits and sweeps)."""
        data = copy.deepcopy(self.raw)
        for key, value in values.items():
            node, last, idx = self._locate(data, key)
            if idx is None:
                node[last] = value
            else:
                cur = node[last]
                if not isinstance(cur, list):
                    cur = [cur, 0.0]
                cur = list(cur)
                cur[idx] = value
                node[last] = cur
        return from_dict(data, self.path)

    def with_aperture(self, aperture_deg: float) -> Scene:
        """The same scene seen by a detector of full aperture ``aperture_deg`` (0: a point
        detector), e.g. the aperture a data file's sidecar records."""
        data = copy.deepcopy(self.raw)
        data.setdefault("detector", {})["aperture_deg"] = aperture_deg
        return from_dict(data, self.path)

    @property
    def aperture_deg(self) -> float:
        return float((self.detector or {}).get("aperture_deg", 0.0))

    def _locate(self, data, key):
        idx = None
        if key.endswith("]") and "[" in key:
            key, _, rest = key.partition("[")
            try:
                idx = int(rest[:-1])
            except ValueError as exc:
                raise SceneError(f"{self.path}: {key}: bad index in {rest!r}") from exc
        parts = key.split(".")
        node = data
        for p in parts[:-1]:
            if not isinstance(node.get(p), dict):
                raise SceneError(f"{self.path}: {key}: no table [{p}] in the scene")
            node = node[p]
        if parts[-1] not in node:
            raise SceneError(f"{self.path}: {key}: not set in the scene")
        return node, parts[-1], idx

    def mechanisms(self) -> list[Mechanism]:
        """The scattering mechanisms this scene requires, each with the reason it is there."""
        out = []
        coat_n = self.coating["index"] if self.coating else None
        rough_top = self.coating.get("roughness") if self.coating else None
        if self.substrate is not None and self.substrate.get("model") == "cook-torrance":
            from .cook_torrance import CookTorranceBRDF
            from .varnished import VarnishedCookTorranceBRDF

            ct = self.substrate["ct"]
            iso = ct["m_parallel"] == ct["m_perpendicular"]
            if coat_n is None and iso:
                out.append(
                    Mechanism(
                        "Cook-Torrance reflection",
                        CookTorranceBRDF(
                            m=ct["m_parallel"],
                            substrate=self.substrate["index"],
                            normalization=ct["normalization"],
                            shadowing=ct["shadowing"],
                        ),
                        "a bare rough metal described by seed 001 (Eq. 7-18)",
                    )
                )
            else:
                out.append(
                    Mechanism(
                        "varnished Cook-Torrance reflection",
                        VarnishedCookTorranceBRDF(
                            m_parallel=ct["m_parallel"],
                            m_perpendicular=ct["m_perpendicular"],
                            varnish=coat_n if coat_n is not None else 1.0,
                            substrate=self.substrate["index"],
                            stroke_angle=ct["stroke_angle"],
                            normalization=ct["normalization"],
                            shadowing=ct["shadowing"],
                            solid_angle=ct["solid_angle"],
                        ),
                        "seed 001's varnish extension (Eq. 19-24)"
                        + ("" if iso else " with brushed (anisotropic) roughness"),
                    )
                )
        elif self.substrate is not None and self.substrate.get("model") == "maxwell-beard":
            from .maxwell_beard import MaxwellBeardBRDF

            mb = self.substrate["mb"]
            out.append(
                Mechanism(
                    "Maxwell-Beard",
                    MaxwellBeardBRDF(
                        slopes=self.substrate["slopes"], substrate=self.substrate["index"], **mb
                    ),
                    "the empirical Maxwell-Beard BRDF (shadowed specular facets + Lambertian + volumetric "
                    "terms, no interface): the model seed 003 Sec. 4 compares its combination with"
                    + ("" if mb["polarized"] else "; published scalar form, depolarizing"),
                )
            )
        elif self.substrate is not None and self.substrate.get("slopes") is not None:
            if coat_n is not None:
                out.append(
                    Mechanism(
                        "subsurface facets",
                        SubsurfaceFacetBRDF(
                            slopes=self.substrate["slopes"], coating=coat_n, substrate=self.substrate["index"]
                        ),
                        "facets (flakes or a rough substrate) under the coating: seed 000's subsurface facet model",
                    )
                )
            else:
                out.append(
                    Mechanism(
                        "exposed facets",
                        FacetBRDF(slopes=self.substrate["slopes"], substrate=self.substrate["index"]),
                        "a rough substrate with no coating: the exposed facet model",
                    )
                )
        if rough_top is not None:
            out.append(
                Mechanism(
                    "rough coating surface",
                    FacetBRDF(slopes=rough_top, substrate=coat_n),
                    "the coating's top surface is rough: facet reflection by the exposed interface",
                )
            )
        if self.volume is not None:
            out = self._volume_mechanisms(out, coat_n, rough_top)
        return out

    def _volume_mechanisms(self, out, n, rough_top):
        """Seed 003: volume scattering in the binder (index = the coating's)."""
        from .diffuse_subsurface import DiffuseSubsurfaceBRDF
        from .phase import HenyeyGreenstein
        from .rough_diffuse import RoughDiffuseBRDF
        from .single_scatter import SingleScatterBRDF

        v = self.volume
        phase = HenyeyGreenstein(g=v["g"], polarized=v["polarized"])
        if rough_top is not None and v["interface"] == "rough":
            # The Monte Carlo model carries the direct reflection by the rough surface
            # (surface=True), so the separate rough-surface facet term is replaced.
            out = [m for m in out if m.name != "rough coating surface"]
            out.append(
                Mechanism(
                    "volume under a rough interface (Monte Carlo)",
                    RoughDiffuseBRDF(
                        slopes=rough_top,
                        n=n,
                        phase=phase,
                        rho=v["rho"],
                        pairs=v["pairs"],
                        seed=v["seed"],
                        surface=True,
                        single=v["single_weight"] if v["single"] else 0.0,
                    ),
                    "a volume scatterer under a rough interface: seed 003 Sec. 2.5 Monte Carlo (two facets "
                    "per path), including the direct reflection by the rough surface",
                )
            )
            return out
        why = (
            "under a smooth interface"
            if rough_top is None
            else (
                "treated as under a smooth interface, as seed 003 does for the red paint (interface = 'smooth')"
            )
        )
        if v["single"]:
            out.append(
                Mechanism(
                    "single volume scattering",
                    v["single_weight"] * SingleScatterBRDF(n=n, phase=phase)
                    if v["single_weight"] != 1.0
                    else SingleScatterBRDF(n=n, phase=phase),
                    f"single scattering by the pigment {why} (seed 003 Eq. 8-20); no Monte Carlo needed",
                )
            )
        if v["rho"] > 0:
            out.append(
                Mechanism(
                    "totally diffuse volume",
                    DiffuseSubsurfaceBRDF(n=n, rho=v["rho"]),
                    f"multiply scattered light {why} (seed 003 Eq. 21-28)",
                )
            )
        return out

    def build(self, tol: float = 1e-3, decisions: dict | None = None) -> Model:
        """The incoherent sum of :meth:`mechanisms` (a single model when there is one),
        under a point source when the scene declares one and it matters, seen through
        the detector's aperture when it matters: each is kept only if it changes the
        in-plane BRDF by more than ``tol`` (relative to the peak), measured at this
        scene's incidence.

        ``decisions`` (from :meth:`decisions`, perhaps of the same scene at other
        parameter values) replaces the measurements: a fit decides once and keeps
        the choice at every evaluation, so its likelihood does not jump where a
        decision would flip."""
        return self._build(tol, decisions)[0]

    def decisions(self, tol: float = 1e-3) -> dict:
        """What :meth:`build` measured: ``{"point_source": bool, "aperture_resolution":
        int or None}`` (None: the aperture is not averaged over)."""
        from .aperture import DetectorAperture
        from .point_source import PointSourceBRDF

        m = self.build(tol)
        res = m.resolution if isinstance(m, DetectorAperture) else None
        inner = m.model if isinstance(m, DetectorAperture) else m
        return {"point_source": isinstance(inner, PointSourceBRDF), "aperture_resolution": res}

    def source_decision(self, tol: float = 1e-3) -> str:
        """Why the source is evaluated as it is (measured, see :meth:`build`)."""
        return self._build(tol)[1]

    def aperture_decision(self, tol: float = 1e-3) -> str:
        """Why the detector aperture is or is not averaged over (measured, see :meth:`build`)."""
        return self._build(tol)[2]

    def _build(self, tol, decisions=None):
        mech = self.mechanisms()
        if not mech:
            raise SceneError(
                f"{self.path}: the scene declares no scattering mechanism (a flat substrate and a smooth "
                "coating only reflect specularly); add [substrate] distribution, [coating.roughness] or [volume]"
            )
        total = mech[0].model
        for m in mech[1:]:
            total = total + m.model
        fixed = decisions or {}
        total, why_source = self._source(total, tol, fixed.get("point_source"))
        total, why_aperture = self._aperture(total, tol, fixed.get("aperture_resolution", ...))
        return total, why_source, why_aperture

    def _probe(self):
        """In-plane probe geometries for the measured decisions: 69 angles from -85 to 85
        deg plus 41 within 5 deg of the specular direction (where narrow peaks live)."""
        import numpy as np

        from .geometry import signed_inplane

        spec = math.degrees(self.theta_i)
        x = np.concatenate([np.linspace(-85.0, 85.0, 69), np.linspace(spec - 5.0, spec + 5.0, 41)])
        x = x[np.abs(x) <= 89.9]
        return signed_inplane(np.radians(x))

    def _deviation(self, a, b):
        """max |f_b - f_a| over the probe, relative to the peak of f_a."""
        import numpy as np

        tr, pr = self._probe()
        fa, fb = a.brdf(self.theta_i, tr, pr), b.brdf(self.theta_i, tr, pr)
        return float(np.max(np.abs(fb - fa)) / max(np.max(fa), 1e-300))

    def _source(self, total, tol, keep=None):
        if self.source != "point":
            return total, "collimated source"
        from .point_source import PointSourceBRDF

        wrapped = PointSourceBRDF(model=total, distance=self.distance_mm, sample_radius=self.sample_radius_mm)
        if keep is not None:
            return (
                (wrapped, "point source kept (decided beforehand)")
                if keep
                else (
                    total,
                    "point source evaluated as collimated (decided beforehand)",
                )
            )
        dev = self._deviation(total, wrapped)
        if dev <= tol:
            return total, (
                f"point source at d/R = {self.distance_mm / self.sample_radius_mm:g} evaluated as collimated: "
                f"measured max deviation {dev:.2g} of the peak <= tol {tol:g}"
            )
        return wrapped, (
            f"point source at d/R = {self.distance_mm / self.sample_radius_mm:g} kept (seed 001 Eq. 28): "
            f"it changes the in-plane BRDF by {dev:.2g} of the peak > tol {tol:g}"
        )

    def _aperture(self, total, tol, resolution=...):
        """The detector aperture, kept when averaging over it changes the in-plane BRDF by
        more than ``tol`` of the peak; its quadrature resolution is the smallest whose
        doubling changes the result by at most ``tol / 10`` (both measured here, unless
        ``resolution`` gives the decision: None to neglect it, an int to keep it)."""
        deg = self.aperture_deg
        if deg == 0.0:
            return total, "point detector (no aperture declared)"
        from .aperture import DetectorAperture

        if resolution is None:
            return total, f"detector aperture {deg:g} deg neglected (decided beforehand)"
        if resolution is not ...:
            return DetectorAperture(model=total, aperture=math.radians(deg), resolution=resolution), (
                f"detector aperture {deg:g} deg kept at quadrature resolution {resolution} (decided beforehand)"
            )

        res, prev = 1, DetectorAperture(model=total, aperture=math.radians(deg), resolution=1)
        while res < 64:
            nxt = prev.replace(resolution=2 * res)
            if self._deviation(nxt, prev) <= 0.1 * tol:
                break
            res, prev = 2 * res, nxt
        dev = self._deviation(total, prev)
        if dev <= tol:
            return total, (
                f"detector aperture {deg:g} deg neglected: averaging over it changes the in-plane BRDF by "
                f"{dev:.2g} of the peak <= tol {tol:g} (measured)"
            )
        return prev, (
            f"detector aperture {deg:g} deg kept: averaging over it changes the in-plane BRDF by {dev:.2g} of "
            f"the peak > tol {tol:g} (measured); quadrature resolution {res} (doubling it changes <= tol/10)"
        )

    def describe(self, tol: float = 1e-3) -> str:
        lines = [f"scene {self.name!r} ({self.path})"]
        for m in self.mechanisms():
            lines.append(f"  - {m.name}: {type(m.model).__name__} — {m.why}")
        if self.mechanisms():
            _, why_source, why_aperture = self._build(tol)
            lines.append(f"  - source: {why_source}")
            lines.append(f"  - detector: {why_aperture}")
        return "\n".join(lines)


def _err(path, key, msg):
    return SceneError(f"{path}: {key}: {msg}")


def _unknown(path, section, table, allowed):
    for k in table:
        if k not in allowed:
            raise _err(path, f"{section}{k}", f"unknown key; allowed: {', '.join(sorted(allowed))}")


def _number(path, key, value, low=None, high=None, low_open=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _err(path, key, f"must be a finite number; got {value!r}")
    if low is not None and (value < low or (low_open and value == low)):
        raise _err(path, key, f"must be {'>' if low_open else '>='} {low:g}; got {value!r}")
    if high is not None and value > high:
        raise _err(path, key, f"must be <= {high:g}; got {value!r}")
    return float(value)


def _index(path, key, value):
    if value == "inf":
        return math.inf
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        z = complex(float(value), 0.0)
    elif isinstance(value, list) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value):
        z = complex(float(value[0]), float(value[1]))
    else:
        raise _err(path, key, f'must be a number n, a pair [n, k], or "inf"; got {value!r}')
    if not (math.isfinite(z.real) and math.isfinite(z.imag)) or z.real <= 0 or z.imag < 0:
        raise _err(path, key, f"must have n > 0 and k >= 0; got {value!r}")
    return z


def _distribution(path, section, table):
    kind = table.get("distribution")
    if kind not in DISTRIBUTIONS:
        raise _err(path, f"{section}distribution", f"must be one of {', '.join(DISTRIBUTIONS)}; got {kind!r}")
    cls, names = DISTRIBUTIONS[kind]
    kwargs = {}
    for name in names:
        if name not in table:
            if name in ("coverage", "rotation_deg"):
                continue
            raise _err(path, f"{section}{name}", f"required for distribution {kind!r}")
        v = _number(path, f"{section}{name}", table[name])
        if name.endswith("_deg"):
            kwargs[name[:-4]] = math.radians(v)
        else:
            kwargs[name] = v
    try:
        return cls(**kwargs)
    except ValueError as exc:
        raise _err(path, f"{section}{kind}", str(exc)) from exc


_CT_KEYS = (
    "m",
    "m_parallel",
    "m_perpendicular",
    "stroke_angle_deg",
    "normalization",
    "shadowing",
    "solid_angle",
)


def _cook_torrance(path, s):
    """Seed 001 roughness: ``m`` (isotropic) or ``m_parallel``/``m_perpendicular`` and
    ``stroke_angle_deg`` (brushed); normalization, shadowing and the varnish's
    solid-angle convention default to the energy-consistent choices."""
    out = {}
    if "m" in s:
        if "m_parallel" in s or "m_perpendicular" in s:
            raise _err(path, "[substrate] m", "give either m or m_parallel and m_perpendicular, not both")
        out["m_parallel"] = out["m_perpendicular"] = _number(
            path, "[substrate] m", s["m"], 0.0, low_open=True
        )
    else:
        for k in ("m_parallel", "m_perpendicular"):
            if k not in s:
                raise _err(path, f"[substrate] {k}", "required for model = 'cook-torrance' (or give m)")
            out[k] = _number(path, f"[substrate] {k}", s[k], 0.0, low_open=True)
    out["stroke_angle"] = math.radians(
        _number(path, "[substrate] stroke_angle_deg", s.get("stroke_angle_deg", 0.0))
    )
    for key, allowed, default in (
        ("normalization", ("energy", "published"), "energy"),
        ("shadowing", ("blinn", "none"), "blinn"),
        ("solid_angle", ("refracted", "published"), "refracted"),
    ):
        v = s.get(key, default)
        if v not in allowed:
            raise _err(path, f"[substrate] {key}", f"must be one of {', '.join(allowed)}; got {v!r}")
        out[key] = v
    return out


_SUBSTRATE_MODELS = ("facet", "cook-torrance", "maxwell-beard")
_MB_KEYS = ("rho_d", "rho_v", "tau_deg", "omega_deg", "polarized")


def _maxwell_beard(path, s, data):
    """Maxwell-Beard's own parameters (:class:`models.MaxwellBeardBRDF`); the specular
    term's slopes come from ``distribution``.  The model has no interface, so a
    ``[coating]`` or ``[volume]`` beside it would be double counting: refused."""
    from .maxwell_beard import MaxwellBeardBRDF

    for table in ("coating", "volume"):
        if table in data:
            raise _err(
                path,
                f"[{table}]",
                "not with [substrate] model = 'maxwell-beard': the model has no interface and carries its "
                "own diffuse (rho_d) and volumetric (rho_v) terms",
            )
    if "distribution" not in s:
        raise _err(
            path, "[substrate] distribution", "required for model = 'maxwell-beard' (the specular facet term)"
        )
    fields = {p.name: p for p in MaxwellBeardBRDF.parameters()}
    out = {}
    for key in ("rho_d", "rho_v"):
        out[key] = _number(path, f"[substrate] {key}", s.get(key, fields[key].default), 0.0)
    for key in ("tau", "omega"):
        deg = _number(
            path, f"[substrate] {key}_deg", s.get(f"{key}_deg", math.degrees(fields[key].default)), 0.0,
            low_open=True,
        )  # fmt: skip
        out[key] = math.radians(deg)
    pol = s.get("polarized", True)
    if not isinstance(pol, bool):
        raise _err(path, "[substrate] polarized", f"must be true or false; got {pol!r}")
    out["polarized"] = pol
    return out


_VOLUME_KEYS = {"rho", "single", "single_weight", "g", "polarized", "interface", "pairs", "seed"}


def _volume(path, v, coating):
    """``[volume]``: a pigment in the binder (seed 003).  The binder's index is the
    coating's, so a ``[coating]`` table is required."""
    if not isinstance(v, dict):
        raise _err(path, "[volume]", "must be a table")
    _unknown(path, "[volume] ", v, _VOLUME_KEYS)
    if coating is None:
        raise _err(path, "[volume]", "needs a [coating] table: its index is the binder's index")
    out = {
        "rho": _number(path, "[volume] rho", v.get("rho", 0.0), 0.0, 1.0),
        "g": _number(path, "[volume] g", v.get("g", 0.0), -0.999999, 0.999999),
        "single_weight": _number(path, "[volume] single_weight", v.get("single_weight", 1.0), 0.0),
    }
    for key, default in (("single", True), ("polarized", True)):
        val = v.get(key, default)
        if not isinstance(val, bool):
            raise _err(path, f"[volume] {key}", f"must be true or false; got {val!r}")
        out[key] = val
    interface = v.get("interface", "rough")
    if interface not in ("rough", "smooth"):
        raise _err(
            path,
            "[volume] interface",
            f"must be 'rough' (Monte Carlo under a rough coating) or 'smooth'; got {interface!r}",
        )
    out["interface"] = interface
    pairs = v.get("pairs", 5000)
    if isinstance(pairs, bool) or not isinstance(pairs, int) or not 2 <= pairs <= 10**7:
        raise _err(path, "[volume] pairs", f"must be an integer in [2, 10^7]; got {pairs!r}")
    out["pairs"] = pairs
    seed = v.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _err(path, "[volume] seed", f"must be an integer >= 0; got {seed!r}")
    out["seed"] = seed
    if out["rho"] == 0 and not out["single"]:
        raise _err(path, "[volume]", "declares no scattering: set rho > 0 or single = true")
    return out


def loads(text: str, path: str = "<scene>") -> Scene:
    """Parse and validate scene TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from exc
    return from_dict(data, path)


def from_dict(data: dict, path: str = "<scene>") -> Scene:
    """Validate a scene given as the dict a TOML file parses to."""
    _unknown(path, "", data, _TOP)
    name = data.get("name")
    if not isinstance(name, str) or not name.strip():
        raise _err(path, "name", "a non-empty string is required")
    ill = data.get("illumination")
    if not isinstance(ill, dict):
        raise _err(path, "[illumination]", "the table is required (theta_i_deg at least)")
    _unknown(path, "[illumination] ", ill, _ILLUM)
    if "theta_i_deg" not in ill:
        raise _err(path, "[illumination] theta_i_deg", "required, in [0, 90]")
    theta_i = math.radians(_number(path, "[illumination] theta_i_deg", ill["theta_i_deg"], 0.0, 90.0))
    try:
        pol = tuple(float(x) for x in stokes(ill.get("polarization", "unpolarized")))
    except ValueError as exc:
        raise _err(path, "[illumination] polarization", str(exc)) from exc
    wl = ill.get("wavelength_nm")
    wl = None if wl is None else _number(path, "[illumination] wavelength_nm", wl, 0.0, low_open=True)
    source = ill.get("source", "collimated")
    if source not in ("collimated", "point"):
        raise _err(path, "[illumination] source", f"must be 'collimated' or 'point'; got {source!r}")
    dist = rad = None
    if source == "point":
        for key in ("distance_mm", "sample_radius_mm"):
            if key not in ill:
                raise _err(
                    path, f"[illumination] {key}", "required for source = 'point' (a finite number > 0)"
                )
        dist = _number(path, "[illumination] distance_mm", ill["distance_mm"], 0.0, low_open=True)
        rad = _number(path, "[illumination] sample_radius_mm", ill["sample_radius_mm"], 0.0, low_open=True)
        if rad > dist:
            raise _err(path, "[illumination] sample_radius_mm", "must not exceed distance_mm")
    coating = None
    if "coating" in data:
        c = data["coating"]
        _unknown(path, "[coating] ", c, {"index", "roughness"})
        if "index" not in c:
            raise _err(path, "[coating] index", "required: a real index >= 1")
        n = _number(path, "[coating] index", c["index"], 1.0)
        coating = {"index": n}
        if "roughness" in c:
            coating["roughness"] = _distribution(path, "[coating.roughness] ", c["roughness"])
    substrate = None
    if "substrate" in data:
        s = data["substrate"]
        allowed = {"index", "distribution", "model"} | {k for _, ks in DISTRIBUTIONS.values() for k in ks}
        allowed |= set(_CT_KEYS) | set(_MB_KEYS)
        _unknown(path, "[substrate] ", s, allowed)
        if "index" not in s:
            raise _err(path, "[substrate] index", 'required: n, [n, k] or "inf"')
        substrate = {"index": _index(path, "[substrate] index", s["index"])}
        kind = s.get("model", "facet")
        if kind not in _SUBSTRATE_MODELS:
            raise _err(
                path, "[substrate] model", f"must be one of {', '.join(_SUBSTRATE_MODELS)}; got {kind!r}"
            )
        substrate["model"] = kind
        for keys, owner in ((_CT_KEYS, "cook-torrance"), (_MB_KEYS, "maxwell-beard")):
            for k in keys:
                if k in s and kind != owner:
                    raise _err(path, f"[substrate] {k}", f"only for model = {owner!r}")
        if kind == "cook-torrance":
            substrate["slopes"] = None
            substrate["ct"] = _cook_torrance(path, s)
        elif kind == "maxwell-beard":
            substrate["mb"] = _maxwell_beard(path, s, data)
            substrate["slopes"] = _distribution(path, "[substrate] ", s)
        else:
            substrate["slopes"] = _distribution(path, "[substrate] ", s) if "distribution" in s else None
    volume = None
    if "volume" in data:
        volume = _volume(path, data["volume"], coating)
    detector = data.get("detector")
    if detector is not None:
        _unknown(path, "[detector] ", detector, {"aperture_deg"})
        detector = {
            "aperture_deg": _number(
                path, "[detector] aperture_deg", detector.get("aperture_deg", 0.0), 0.0, 90.0
            )
        }
    return Scene(
        name=name,
        path=path,
        theta_i=theta_i,
        polarization=pol,
        wavelength_nm=wl,
        source=source,
        distance_mm=dist,
        sample_radius_mm=rad,
        coating=coating,
        substrate=substrate,
        volume=volume,
        detector=detector,
        fit=data.get("fit"),
        raw=copy.deepcopy(data),
    )


def load(path) -> Scene:
    """Read and validate a scene file."""
    path = str(path)
    try:
        with open(path, "rb") as fh:
            text = fh.read().decode("utf-8")
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror})") from exc
    return loads(text, path)
