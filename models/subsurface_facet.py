"""Facets under a smooth, non-absorbing coating (seed 000, the paper's model)."""

from __future__ import annotations

from dataclasses import dataclass

from .facet import _FacetModel, _index_or_stack
from .params import param
from .shadowing import SHADOWING
from .slopes import ExponentialSlopes, SlopeDistribution

__all__ = ["SubsurfaceFacetBRDF"]


@dataclass(frozen=True)
class SubsurfaceFacetBRDF(_FacetModel):
    """Flakes or a rough interface beneath a smooth transparent coating (seed 000).

    A ray refracts into the coating (Eq. 2-4, 9-10), reflects from the facet
    that connects the two internal directions (Eq. 5-7, 11), and refracts out
    (Eq. 12-15); the Jones matrix is ``q`` of Eq. 16-18 and the Mueller BRDF is
    Eq. 49, ``P3 / (4 cos ti cos tr cos^4 theta_n) Mueller(q)``.  Single
    scattering only: rays reflected back by the coating's underside (total
    internal reflection included) are lost, which is why Table I's integrated
    reflectances fall with coating index.  Light reflected by the coating's top
    surface is not part of this model (add a specular or :class:`FacetBRDF`
    term for it).  SCATMECH: ``Subsurface_Facet_BRDF_Model`` (``overcoat``).

    Parameters
    ----------
    slopes : SlopeDistribution
        Facet slope distribution ``P3^xy`` (coverage ``C`` scales the result).
    coating : float
        Real index ``n >= 1`` of the coating (1 reproduces :class:`FacetBRDF`).
    substrate : complex, math.inf or FilmStack
        Index of the flakes / substrate, ``n + ik`` with ``k >= 0``, ``inf``, or a
        :class:`models.FilmStack` (films on the flakes, seen from the coating: e.g.
        mica flakes with a TiO2 film).
    shadowing : str
        ``"none"`` (seed 000), ``"smith"`` or ``"smith-correlated"``
        (:mod:`models.shadowing`), evaluated inside the coating with the refracted
        directions: the facets mask the internal rays.
    """

    slopes: SlopeDistribution = param(ExponentialSlopes(0.1), "facet slope distribution", kind="object")
    coating: float = param(1.5, "coating index (real, non-absorbing)", kind="real_index", low=1.0)
    substrate: complex = param(
        1.37 + 7.62j,
        "flake/substrate index n + ik (inf: perfect conductor) or a models.FilmStack",
        kind="index",
        check=_index_or_stack,
    )
    shadowing: str = param("none", "shadowing-masking (inside the coating)", kind="choice", choices=SHADOWING)

    def _coating(self) -> float:
        return self.coating
