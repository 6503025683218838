"""Facets under a smooth, non-absorbing coating (seed 000, the paper's model), optionally
with thin films on the coating's top surface.

Films on the coating (``coating_films``, ambient | films | coating).  Seed 000 Eq. 16-18
write the Jones matrix as ``q = diag(t_r) Q diag(t_i)`` with ``t_i = t(theta_i; 1, n)``
(Eq. 14, entrance) and ``t_r = t(theta_r; 1, n)`` (Eq. 15, exit) for s and p, ``Q`` the
facet's reflection in the internal rays' bases.  With films each factor becomes the
stack's complex amplitude (:mod:`scatterbench.models.smooth_interface`, F1-F2):

    t_i -> t_01(theta_i)                        entrance: ambient -> films -> coating
    t_r -> t_10(theta_r') kz_0 / kz_s           exit: coating -> films -> ambient,
                                                kz_0 = cos theta_r, kz_s = n cos theta_r'

so ``q_ab = t_r,a Q_ab t_i,b`` is a product of complex numbers (the films' s/p phase
difference reaches the Mueller matrix's U and V rows).  Nothing else of Eq. 2-13, 19 and 49
changes: planar films bend no ray, so the internal directions, the facet, its slope density
and the Jacobian are the bare coating's.  Energy: ``|t|^2`` times the ``kz`` ratios are the
stack's transmittances (F3), below ``1 - R`` with an absorbing film; reciprocity: the stack
has ``t_10 kz_0 = t_01 kz_s`` (:mod:`scatterbench.models.thin_film`, (R)), so the exit factor at
``theta`` equals the entrance factor at ``theta`` and ``q`` keeps Eq. 16-18's symmetry
(F4; tested to the bare model's tolerance).  Without films the model is seed 000's, the
compiled kernel included.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

from .constraints import Options
from .facet import _FacetModel
from .facts import Correspondence, scatmech_index
from .params import coating_param, param
from .shadowing import SHADOWING
from .slopes import SLOPES, ExponentialSlopes, SlopeDistribution
from .thin_film import INDEX_OR_STACK, FilmedCoating, Films, coating_films_param

__all__ = ["SubsurfaceFacetBRDF"]


@dataclass(frozen=True)
class SubsurfaceFacetBRDF(FilmedCoating, _FacetModel):
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
        :class:`scatterbench.models.FilmStack` (films on the flakes, seen from the coating: e.g.
        mica flakes with a TiO2 film).
    shadowing : str
        ``"none"`` (seed 000), ``"smith"`` or ``"smith-correlated"``
        (:mod:`scatterbench.models.shadowing`), evaluated inside the coating with the refracted
        directions: the facets mask the internal rays.
    coating_films : Films or None
        Thin films on the coating's top surface (:class:`scatterbench.models.Films`: layers from the
        ambient down, and the wavelength), on the index ``coating``: e.g. an anti-reflection
        film.  ``None`` (default): the bare coating of seed 000.  Module docstring: the
        films' complex transmission amplitudes replace Eq. 14-15's ``t(theta; 1, n)``.
    """

    slopes: SlopeDistribution = param(ExponentialSlopes(0.1), "facet slope distribution", SLOPES)
    coating: float = coating_param(1.5, "coating index (real, non-absorbing)")
    substrate: complex = param(
        1.37 + 7.62j,
        "flake/substrate index n + ik (inf: perfect conductor) or a models.FilmStack",
        INDEX_OR_STACK,
    )
    shadowing: str = param("none", "shadowing-masking (inside the coating)", Options(*SHADOWING))
    coating_films: Films = coating_films_param("thin films on the coating's top surface (None: bare)")

    correspondence = Correspondence(
        "seed 000 Eq. 2-18, 49 (Table I)", "``Subsurface_Facet_BRDF_Model`` (``overcoat``)"
    )
    #: the kit's instance: slopes and coating of committed SCATMECH reference values
    #: (references/data/scatmech_facet.csv), so that its ``scatmech`` check compares with them
    kit_variant = MappingProxyType({"slopes": ExponentialSlopes(0.05), "coating": 2.2})

    @property
    def scatmech(self):
        """SCATMECH's ``Subsurface_Facet_BRDF_Model`` (``overcoat`` = coating) with these
        parameters, or ``None``: it has no shadowing, no films and the exponential and
        Gaussian families only."""
        sdf, sub = self.slopes.scatmech_parameters(), scatmech_index(self.substrate)
        coat = scatmech_index(self.coating)
        if sdf is None or sub is None or coat is None or self.shadowing != "none" or self.coating_films:
            return None
        return "Subsurface_Facet_BRDF_Model", {"substrate": sub, "overcoat": coat, **sdf}

    def _coating(self) -> float:
        return self.coating

    def _top(self):
        return self._top_stack
