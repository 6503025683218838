"""Scenes and the mechanisms they build: each example scene's decisions and in-plane BRDF."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from scatterbench import references
from scatterbench.models import scene as scene_mod

from ..core import figure_block, table_block
from ._common import finish, inplane, plt

__all__ = ["ScenesData", "compute", "render"]


@dataclass(frozen=True)
class ScenesData:
    """``rows``: one per scene file; ``x``: signed theta_r (deg); ``curves``: (name, BRDF over
    ``x`` for the scene's declared incident polarization) for each scene that builds mechanisms."""

    rows: tuple
    x: np.ndarray
    curves: tuple


def _scene(path, x):
    """The row of one scene file and its curve (None if it builds nothing or fails to load)."""

    try:
        sc = scene_mod.load(path)
        mech = sc.mechanisms()
    except ValueError as exc:
        row = {
            "scene": os.path.basename(path),
            "mechanisms": "",
            "why": f"error: {exc}",
            "source and detector": "",
        }
        return row, None
    row = {
        "scene": sc.name,
        "mechanisms": ", ".join(f"{m.name} ({type(m.model).__name__})" for m in mech),
        "why": "; ".join(m.why for m in mech),
        "source and detector": f"{sc.source_decision()}; {sc.aperture_decision()}" if mech else "",
    }
    if not mech:
        return row, None
    return row, (sc.name, inplane(sc.build(), sc.theta_i, x, incident=np.array(sc.polarization))["brdf"])


def compute(ctx):
    x = np.linspace(-89, 89, 179)
    paths = list(references.scene_paths()) + list(ctx.cache.get("extra_scenes", []))
    rows, curves = [], []
    for path in paths:
        row, curve = _scene(path, x)
        rows.append(row)
        if curve is not None:
            curves.append(curve)
    return ScenesData(tuple(rows), x, tuple(curves))


def _draw(d):
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for name, f in d.curves:
        ax.semilogy(d.x, np.maximum(f, 1e-10), label=name)
    return finish(fig, ax, "scattering angle theta_r (deg)", "BRDF (1/sr)", 7)


def render(s, d: ScenesData):
    s.blocks.append(
        figure_block(
            _draw(d),
            "In-plane BRDF of each example scene for its declared incident polarization (with its point source "
            "and detector aperture where they matter, as measured in the table)",
        )
    )
    s.blocks.append(table_block(s, "scenes", ["scene", "mechanisms", "why", "source and detector"], d.rows))
