"""The scene: a sample and a measurement described once, validated, and the models it builds."""

from __future__ import annotations

import copy
import re
import tomllib
from dataclasses import dataclass, field

from ..base import Model
from ..text import long_digits, read_utf8, where
from . import editing
from .assembly import Mechanism, mechanisms
from .decisions import Assembly, assemble
from .schema import SceneError, check_structure, parse

__all__ = ["Scene", "load", "loads", "from_dict"]


@dataclass(frozen=True)
class Scene:
    """A validated scene file (see :mod:`scatterbench.models.scene` for the schema).  Angles in radians."""

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
    #: assemblies measured so far, by tolerance (a scene is immutable: measure once)
    _assemblies: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    # -- dotted keys ------------------------------------------------------------------
    def get_value(self, key: str):
        """The raw value at a dotted key of the scene file, e.g. ``substrate.sigma``,
        ``coating.index``, ``substrate.index[1]`` (k of an [n, k] index)."""
        return editing.get_value(self.raw, key, self.path)

    def with_values(self, values: dict) -> Scene:
        """A new, re-validated scene with the given dotted keys set (for fits and sweeps)."""
        return from_dict(editing.with_values(self.raw, values, self.path), self.path)

    def with_aperture(self, aperture_deg: float) -> Scene:
        """The same scene seen by a detector of full aperture ``aperture_deg`` (0: a point
        detector), e.g. the aperture a data file's sidecar records."""
        data = copy.deepcopy(self.raw)
        data.setdefault("detector", {})["aperture_deg"] = aperture_deg
        return from_dict(data, self.path)

    @property
    def aperture_deg(self) -> float:
        return float((self.detector or {}).get("aperture_deg", 0.0))

    # -- models -------------------------------------------------------------------------
    def mechanisms(self) -> list[Mechanism]:
        """The scattering mechanisms this scene requires, each with the reason it is there."""
        return mechanisms(self.substrate, self.coating, self.volume)

    def assemble(self, tol: float = 1e-3, decisions: dict | None = None) -> Assembly:
        """The scene's model with its mechanisms and the decisions taken: the point source
        and the detector aperture are kept only if they change the in-plane BRDF by more
        than ``tol`` (relative to the peak), measured at this scene's incidence, once per
        ``tol``.  ``decisions`` (from :meth:`decisions`, perhaps of the same scene at other
        parameter values) replaces the measurements: a fit decides once and keeps the
        choice at every evaluation, so its likelihood does not jump where a decision
        would flip."""
        if decisions is not None:
            return assemble(self, self.mechanisms(), tol, decisions)
        if tol not in self._assemblies:
            self._assemblies[tol] = assemble(self, self.mechanisms(), tol)
        return self._assemblies[tol]

    def build(self, tol: float = 1e-3, decisions: dict | None = None) -> Model:
        """The incoherent sum of :meth:`mechanisms` (a single model when there is one),
        under a point source and behind the detector's aperture where they matter
        (:meth:`assemble`)."""
        return self.assemble(tol, decisions).model

    def decisions(self, tol: float = 1e-3) -> dict:
        """What :meth:`build` measured: ``{"point_source": bool, "aperture_resolution":
        int or None}`` (None: the aperture is not averaged over)."""
        return dict(self.assemble(tol).decisions)

    def source_decision(self, tol: float = 1e-3) -> str:
        """Why the source is evaluated as it is (measured, see :meth:`assemble`)."""
        return self.assemble(tol).source_reason

    def aperture_decision(self, tol: float = 1e-3) -> str:
        """Why the detector aperture is or is not averaged over (measured, see :meth:`assemble`)."""
        return self.assemble(tol).aperture_reason

    def describe(self, tol: float = 1e-3) -> str:
        """The scene, its mechanisms and why, and the source and detector decisions."""
        lines = [f"scene {self.name!r} ({self.path})"]
        if not self.mechanisms():
            return lines[0]
        a = self.assemble(tol)
        for m in a.mechanisms:
            lines.append(f"  - {m.name}: {type(m.model).__name__} — {m.why}")
        lines.append(f"  - source: {a.source_reason}")
        lines.append(f"  - detector: {a.aperture_reason}")
        return "\n".join(lines)


def from_dict(data: dict, path: str = "<scene>") -> Scene:
    """Validate a scene given as the dict a TOML file parses to."""
    check_structure(data, path)  # before anything walks it: depth and numbers a float can hold
    return Scene(path=path, raw=copy.deepcopy(data), **parse(data, path))


def _at(text, offset):
    """``line:column`` (1-based) of a character offset of ``text``, as the errors show it."""
    return "{}:{}".format(*where(text, offset))


def _toml_error(text, path, exc):
    """A :class:`SceneError` for a TOML syntax error, ``file:line:column`` first."""
    msg = str(exc)
    m = re.search(r" \(at line (\d+), column (\d+)\)$", msg)
    if m:
        return SceneError(f"{path}:{m.group(1)}:{m.group(2)}: not valid TOML: {msg[: m.start()]}")
    if msg.endswith(" (at end of document)"):
        return SceneError(f"{path}:{_at(text, len(text))}: not valid TOML: {msg[:-21]} (at the end)")
    return SceneError(f"{path}: not valid TOML: {msg}")


def loads(text: str, path: str = "<scene>") -> Scene:
    """Parse and validate scene TOML text (a leading byte-order mark is ignored)."""
    text = text.removeprefix("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _toml_error(text, path, exc) from exc
    except RecursionError as exc:
        raise SceneError(
            f"{path}: not valid TOML for a scene: arrays or inline tables nested too deeply for the parser"
        ) from exc
    except ValueError as exc:  # Python refuses to convert an integer of thousands of digits
        digits = long_digits(text)
        if digits is None:
            raise SceneError(f"{path}: not valid TOML: {exc}") from exc
        start = text.rfind("\n", 0, digits.start()) + 1
        key = text[start : digits.start()].split("=")[0].strip() or "value"
        raise SceneError(
            f"{path}:{_at(text, digits.start())}: {key}: a number of {len(digits.group())} digits "
            "is too long to read"
        ) from exc
    return from_dict(data, path)


def load(path) -> Scene:
    """Read and validate a scene file (UTF-8, with or without a byte-order mark)."""
    path = str(path)
    text = read_utf8(
        path,
        "scene file",
        lambda at, msg: SceneError(f"{path}:{at[0]}:{at[1]}: {msg}" if at else f"{path}: {msg}"),
    )
    return loads(text, path)
