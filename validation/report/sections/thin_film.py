"""Thin-film interference flakes: the pearlescent example scene's spectrum and colour
versus aspecular angle (:mod:`scatterbench.validation.studies.colour`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.studies.colour import colour_travel

from ..core import figure_block, table_block, text_block
from ._common import plt

__all__ = ["ThinFilmData", "SCENE", "compute", "render"]

#: the shipped example scene: mica flakes with a TiO2 film in a clear coat
SCENE = "pearlescent_mica_tio2.toml"


@dataclass(frozen=True)
class ThinFilmData:
    """The scene's name and stack, and its :class:`~scatterbench.validation.studies.colour.ColourTravel`."""

    scene_name: str
    stack: str
    travel: object
    rows: tuple


def compute(ctx):

    sc = scene.load(references.scene_path(SCENE))
    model = sc.mechanisms()[0].model  # the flakes: a facet model whose substrate is the stack
    t = colour_travel(model, sc.theta_i)
    rows = tuple(
        {
            "aspecular (deg)": a,
            "flake-local angle (deg)": loc,
            "peak (nm)": float(t.wavelengths_nm[int(np.argmax(r))]),
            "peak reflectance": float(np.max(r)),
            "dominant wavelength (nm)": dom,
            "sRGB": "#" + "".join(f"{round(255 * float(v)):02x}" for v in rgb),
        }
        for a, loc, r, dom, rgb in zip(
            t.aspecular_deg, t.local_deg, t.reflectance, t.dominant_nm, t.srgb, strict=True
        )
    )
    return ThinFilmData(sc.name, repr(model.substrate), t, rows)


def _draw(d):
    t = d.travel
    fig, (ax, sw) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [3, 1]})
    for a, r, rgb in zip(t.aspecular_deg, t.reflectance, t.srgb, strict=True):
        ax.plot(t.wavelengths_nm, r, color=np.clip(rgb, 0, 1), lw=1.8, label=f"{a:g} deg")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("reflectance relative to a mirror flake")
    ax.legend(title="aspecular", fontsize=7)
    for k, rgb in enumerate(t.srgb):
        sw.add_patch(plt.Rectangle((0, k), 1, 0.9, color=np.clip(rgb, 0, 1)))
    sw.set_xlim(0, 1)
    sw.set_ylim(len(t.srgb), -0.1)
    sw.set_yticks(np.arange(len(t.srgb)) + 0.45, [f"{a:g} deg" for a in t.aspecular_deg])
    sw.set_xticks([])
    sw.set_title("sRGB (D65, CIE 1931 2 deg)", fontsize=9)
    fig.tight_layout()
    return fig


def render(s, d: ThinFilmData):
    s.blocks.append(
        text_block(
            f"Scene {SCENE} ({d.scene_name}), lit at {d.travel.theta_i_deg:g} deg; flakes' stack: "
            f"{d.stack}. Spectra are the in-plane BRDF divided by the same model with a "
            "perfect-mirror flake; colours from colour-science's CIE 1931 2-degree functions "
            "under D65."
        )
    )
    s.blocks.append(figure_block(_draw(d), "Thin-film flakes: spectrum and colour versus aspecular angle"))
    fmt = {"flake-local angle (deg)": ".2f", "peak reflectance": ".4f", "dominant wavelength (nm)": ".1f"}
    s.blocks.append(table_block(s, "colour_travel", list(d.rows[0]), d.rows, fmt=fmt))
