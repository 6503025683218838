"""Measured decisions: whether a scene's point source and detector aperture matter.

A scene's mechanisms are summed; a declared point source (seed 001 Eq. 28) and a detector
aperture are kept only when they change the in-plane BRDF by more than ``tol`` of its
peak, measured at the scene's incidence.  :func:`assemble` measures once and returns an
:class:`Assembly` (the model, the mechanisms, the decisions and why); given ``decisions``
(from an earlier assembly, perhaps of the same scene at other parameter values) it
measures nothing, so a fit's likelihood does not jump where a decision would flip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..aperture import DetectorAperture
from ..base import Model
from ..geometry import signed_inplane
from ..point_source import PointSourceBRDF
from .assembly import Mechanism
from .schema import SceneError

__all__ = ["Assembly", "assemble"]

#: a decision not given beforehand (None means "neglect the aperture")
_MEASURE = object()


@dataclass(frozen=True)
class Assembly:
    """A scene built: its model, its mechanisms, the decisions taken and why.

    ``decisions`` is ``{"point_source": bool, "aperture_resolution": int or None}``
    (None: the aperture is not averaged over).
    """

    model: Model
    mechanisms: tuple[Mechanism, ...]
    decisions: dict
    source_reason: str
    aperture_reason: str


def assemble(scene, mechanisms, tol: float = 1e-3, decisions: dict | None = None) -> Assembly:
    """The incoherent sum of ``mechanisms`` (a single model when there is one) under the
    scene's point source and behind its detector aperture where they matter (measured
    against ``tol``, unless ``decisions`` gives them)."""
    if not mechanisms:
        raise SceneError(
            f"{scene.path}: the scene declares no scattering mechanism (a flat substrate and a smooth "
            "coating only reflect specularly); add [substrate] distribution, [coating.roughness] or [volume]"
        )
    total = mechanisms[0].model
    for m in mechanisms[1:]:
        total = total + m.model
    fixed = decisions or {}
    total, why_source = _source(scene, total, tol, fixed.get("point_source"))
    total, why_aperture = _aperture(scene, total, tol, fixed.get("aperture_resolution", _MEASURE))
    res = total.resolution if isinstance(total, DetectorAperture) else None
    inner = total.model if isinstance(total, DetectorAperture) else total
    chosen = {"point_source": isinstance(inner, PointSourceBRDF), "aperture_resolution": res}
    return Assembly(total, tuple(mechanisms), chosen, why_source, why_aperture)


def _probe(scene):
    """In-plane probe geometries for the measured decisions: 69 angles from -85 to 85
    deg plus 41 within 5 deg of the specular direction (where narrow peaks live)."""
    spec = math.degrees(scene.theta_i)
    x = np.concatenate([np.linspace(-85.0, 85.0, 69), np.linspace(spec - 5.0, spec + 5.0, 41)])
    x = x[np.abs(x) <= 89.9]
    return signed_inplane(np.radians(x))


def _deviation(scene, a, b):
    """max |f_b - f_a| over the probe, relative to the peak of f_a."""
    tr, pr = _probe(scene)
    fa, fb = a.brdf(scene.theta_i, tr, pr), b.brdf(scene.theta_i, tr, pr)
    return float(np.max(np.abs(fb - fa)) / max(np.max(fa), 1e-300))


def _source(scene, total, tol, keep=None):
    if scene.source != "point":
        return total, "collimated source"
    wrapped = PointSourceBRDF(model=total, distance=scene.distance_mm, sample_radius=scene.sample_radius_mm)
    if keep is not None:
        if keep:
            return wrapped, "point source kept (decided beforehand)"
        return total, "point source evaluated as collimated (decided beforehand)"
    dev = _deviation(scene, total, wrapped)
    ratio = f"d/R = {scene.distance_mm / scene.sample_radius_mm:g}"
    if dev <= tol:
        return total, (
            f"point source at {ratio} evaluated as collimated: "
            f"measured max deviation {dev:.2g} of the peak <= tol {tol:g}"
        )
    return wrapped, (
        f"point source at {ratio} kept (seed 001 Eq. 28): "
        f"it changes the in-plane BRDF by {dev:.2g} of the peak > tol {tol:g}"
    )


def _aperture(scene, total, tol, resolution=_MEASURE):
    """The detector aperture, kept when averaging over it changes the in-plane BRDF by
    more than ``tol`` of the peak; its quadrature resolution is the smallest whose
    doubling changes the result by at most ``tol / 10`` (both measured here, unless
    ``resolution`` gives the decision: None to neglect it, an int to keep it)."""
    deg = scene.aperture_deg
    if deg == 0.0:
        return total, "point detector (no aperture declared)"
    if resolution is None:
        return total, f"detector aperture {deg:g} deg neglected (decided beforehand)"
    if resolution is not _MEASURE:
        return DetectorAperture(model=total, aperture=math.radians(deg), resolution=resolution), (
            f"detector aperture {deg:g} deg kept at quadrature resolution {resolution} (decided beforehand)"
        )
    res, prev = 1, DetectorAperture(model=total, aperture=math.radians(deg), resolution=1)
    while res < 64:
        nxt = prev.replace(resolution=2 * res)
        if _deviation(scene, nxt, prev) <= 0.1 * tol:
            break
        res, prev = 2 * res, nxt
    dev = _deviation(scene, total, prev)
    if dev <= tol:
        return total, (
            f"detector aperture {deg:g} deg neglected: averaging over it changes the in-plane BRDF by "
            f"{dev:.2g} of the peak <= tol {tol:g} (measured)"
        )
    return prev, (
        f"detector aperture {deg:g} deg kept: averaging over it changes the in-plane BRDF by {dev:.2g} of "
        f"the peak > tol {tol:g} (measured); quadrature resolution {res} (doubling it changes <= tol/10)"
    )
