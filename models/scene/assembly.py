"""Mechanism assembly: the models a validated scene declares, each with the reason it is there.

The substrate's mechanism comes from its model's entry in :data:`scatterbench.models.scene.table.TABLE`
(``facet``, ``cook-torrance``, ``maxwell-beard``); the coating's rough top surface and the
volume scatterer (seed 003) follow.  Nothing here measures anything: that is
:mod:`scatterbench.models.scene.decisions`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..base import Model
from ..cook_torrance import CookTorranceBRDF
from ..diffuse_subsurface import DiffuseSubsurfaceBRDF
from ..facet import FacetBRDF
from ..maxwell_beard import MaxwellBeardBRDF
from ..phase import HenyeyGreenstein
from ..rough_diffuse import RoughDiffuseBRDF
from ..rough_subsurface import RoughSubsurfaceBRDF
from ..single_scatter import SingleScatterBRDF
from ..slopes import GaussianSlopes
from ..subsurface_facet import SubsurfaceFacetBRDF
from ..thin_film import FilmStack
from ..varnished import VarnishedCookTorranceBRDF

__all__ = [
    "Mechanism",
    "mechanisms",
    "facet_mechanisms",
    "cook_torrance_mechanisms",
    "maxwell_beard_mechanisms",
    "monte_carlo_volume",
]


@dataclass(frozen=True)
class Mechanism:
    """One scattering mechanism of a scene: its name, its model and why it is there."""

    name: str
    model: Model
    why: str


def monte_carlo_volume(coating: dict | None, volume: dict | None) -> bool:
    """Whether a scene's ``[volume]`` is seed 003 Sec. 2.5's Monte Carlo model under the rough
    coating (a ``[coating.roughness]`` with ``[volume] interface = 'rough'``): the one rule the
    schema's checks and the assembly both apply."""
    return (
        volume is not None
        and coating is not None
        and coating.get("roughness") is not None
        and volume["interface"] == "rough"
    )


def mechanisms(substrate: dict | None, coating: dict | None, volume: dict | None) -> list[Mechanism]:
    """The mechanisms of a scene's validated ``[substrate]``, ``[coating]`` and ``[volume]``."""
    coat_n = coating["index"] if coating else None
    rough_top = coating.get("roughness") if coating else None
    # films on the coating's top ([coating.film]): the schema allows them only where a model takes them
    top = {"coating_films": coating["films"]} if coating and coating.get("films") is not None else {}
    out = [] if substrate is None else substrate["entry"].mechanisms(substrate, coat_n, **top)
    if rough_top is not None:
        surface = top["coating_films"].on(coat_n) if top else coat_n
        out.append(
            Mechanism(
                "rough coating surface",
                FacetBRDF(slopes=rough_top, substrate=surface, shadowing=coating.get("shadowing", "none")),
                "the coating's top surface is rough: facet reflection by the exposed interface"
                + (" (its films on the coating)" if top else ""),
            )
        )
    if volume is not None:
        out = _volume_mechanisms(out, volume, coat_n, rough_top, top, monte_carlo_volume(coating, volume))
    return out


def facet_mechanisms(sub: dict, coat_n, coating_films=None) -> list[Mechanism]:
    """Facets (flakes or a rough substrate), under the coating (and its films) when there is one."""
    if sub["slopes"] is None:
        return []  # a flat substrate only reflects specularly
    kw = {
        "slopes": sub["slopes"],
        "substrate": sub["index"],
        "shadowing": sub["params"].get("shadowing", "none"),
    }
    films = " with thin films on them" if isinstance(sub["index"], FilmStack) else ""
    if coat_n is not None:
        model = SubsurfaceFacetBRDF(coating=coat_n, coating_films=coating_films, **kw)
        why = f"facets (flakes or a rough substrate){films} under the coating: seed 000's subsurface facet model"
        if coating_films is not None:
            why += ", through the films on the coating (their complex transmission amplitudes)"
        return [Mechanism("subsurface facets", model, why)]
    model = FacetBRDF(**kw)
    why = f"a rough substrate{films} with no coating: the exposed facet model"
    return [Mechanism("exposed facets", model, why)]


def cook_torrance_mechanisms(sub: dict, coat_n) -> list[Mechanism]:
    """Seed 001: a bare isotropic metal is Cook-Torrance (Eq. 7-18); a coated or brushed
    one is the varnish extension (Eq. 19-24; ``n_v = 1`` without a coating)."""
    kw = sub["params"]  # slopes (StrokeSlopes), convention, shadowing
    iso = kw["slopes"].isotropic
    if coat_n is None and iso:
        model = CookTorranceBRDF(
            slopes=GaussianSlopes(sigma=kw["slopes"].m_parallel),
            substrate=sub["index"],
            convention=kw["convention"],
            shadowing=kw["shadowing"],
        )
        return [
            Mechanism(
                "Cook-Torrance reflection", model, "a bare rough metal described by seed 001 (Eq. 7-18)"
            )
        ]
    model = VarnishedCookTorranceBRDF(coating=1.0 if coat_n is None else coat_n, substrate=sub["index"], **kw)
    why = "seed 001's varnish extension (Eq. 19-24)" + (
        "" if iso else " with brushed (anisotropic) roughness"
    )
    return [Mechanism("varnished Cook-Torrance reflection", model, why)]


def maxwell_beard_mechanisms(sub: dict, coat_n) -> list[Mechanism]:
    """The empirical Maxwell-Beard BRDF (the scene refuses a coating or volume beside it)."""
    kw = sub["params"]
    model = MaxwellBeardBRDF(slopes=sub["slopes"], substrate=sub["index"], **kw)
    why = (
        "the empirical Maxwell-Beard BRDF (shadowed specular facets + Lambertian + volumetric "
        "terms, no interface): the model seed 003 Sec. 4 compares its combination with"
        + ("" if kw["polarized"] else "; published scalar form, depolarizing")
    )
    return [Mechanism("Maxwell-Beard", model, why)]


def _volume_mechanisms(out, v, n, rough_top, top, monte_carlo):
    """Seed 003: volume scattering in the binder (index = the coating's); ``monte_carlo``:
    :func:`monte_carlo_volume`."""
    phase = HenyeyGreenstein(g=v["g"], polarized=v["polarized"])
    if monte_carlo and v.get("method") == "quadrature":
        model = RoughSubsurfaceBRDF(slopes=rough_top, coating=n, rho=v["rho"])
        why = (
            "a diffuser under a rough interface: seed 003 Sec. 2.5's totally diffuse term, its "
            "expectation over facet pairs by quadrature (the rough surface's reflection is its own term)"
        )
        return out + [Mechanism("volume under a rough interface (quadrature)", model, why)]
    if monte_carlo:
        # The Monte Carlo model carries the direct reflection by the rough surface
        # (surface=True), so the separate rough-surface facet term is replaced.
        out = [m for m in out if m.name != "rough coating surface"]
        model = RoughDiffuseBRDF(
            slopes=rough_top,
            coating=n,
            phase=phase,
            rho=v["rho"],
            pairs=v["pairs"],
            seed=v["seed"],
            surface=True,
            single=v["single_weight"] if v["single"] else 0.0,
        )
        why = (
            "a volume scatterer under a rough interface: seed 003 Sec. 2.5 Monte Carlo (two facets "
            "per path), including the direct reflection by the rough surface"
        )
        return out + [Mechanism("volume under a rough interface (Monte Carlo)", model, why)]
    under = (
        "under a smooth interface" + (" with films" if top else "")
        if rough_top is None
        else "treated as under a smooth interface, as seed 003 does for the red paint (interface = 'smooth')"
    )
    if v["single"]:
        single = SingleScatterBRDF(coating=n, phase=phase, **top)
        if v["single_weight"] != 1.0:
            single = v["single_weight"] * single
        why = f"single scattering by the pigment {under} (seed 003 Eq. 8-20); no Monte Carlo needed"
        out.append(Mechanism("single volume scattering", single, why))
    if v["rho"] > 0:
        model = DiffuseSubsurfaceBRDF(coating=n, rho=v["rho"], **top)
        out.append(
            Mechanism(
                "totally diffuse volume", model, f"multiply scattered light {under} (seed 003 Eq. 21-28)"
            )
        )
    return out
