"""scatterbench models: polarized light scattering by coated, flake-pigmented,
rough and diffuse surfaces (seeds 000, 001, 003; conventions in DESIGN.md).

Angles are radians; results broadcast and have shape ``broadcast + (4, 4)``.
"""

from .base import CHUNK, Model, Sum
from .facet import FacetBRDF
from .fresnel import fresnel_coefficients, fresnel_reflectance, fresnel_transmittance
from .params import ParamInfo
from .polarization import (
    ellipsometric,
    is_physical,
    jones_to_mueller,
    reciprocal_jones,
    reciprocal_mueller,
    stokes,
)
from .slopes import (
    AnisotropicExponentialSlopes,
    AnisotropicGaussianSlopes,
    AnisotropicGGXSlopes,
    ExponentialAngles,
    ExponentialSlopes,
    GaussianAngles,
    GaussianSlopes,
    GGXSlopes,
    SlopeDistribution,
    TabulatedSlopes,
)
from .subsurface_facet import SubsurfaceFacetBRDF

__all__ = [
    "CHUNK",
    "Model",
    "Sum",
    "ParamInfo",
    "FacetBRDF",
    "SubsurfaceFacetBRDF",
    "SlopeDistribution",
    "ExponentialSlopes",
    "GaussianSlopes",
    "AnisotropicExponentialSlopes",
    "AnisotropicGaussianSlopes",
    "GaussianAngles",
    "ExponentialAngles",
    "TabulatedSlopes",
    "GGXSlopes",
    "AnisotropicGGXSlopes",
    "fresnel_coefficients",
    "fresnel_reflectance",
    "fresnel_transmittance",
    "jones_to_mueller",
    "ellipsometric",
    "is_physical",
    "reciprocal_jones",
    "reciprocal_mueller",
    "stokes",
]


def list_models():
    """Names and parameter listings of every model class (like SCATMECH's model lists)."""
    return "\n\n".join(c.info() for c in Model.registry)


# --- issue 4 (seed 001: varnished metal) -------------------------------------------
from .cook_torrance import CookTorranceBRDF, fresnel_real  # noqa: E402
from .point_source import PointSourceBRDF  # noqa: E402
from .stroke_slopes import StrokeSlopes  # noqa: E402
from .varnished import VarnishedCookTorranceBRDF  # noqa: E402

__all__ += [
    "CookTorranceBRDF",
    "VarnishedCookTorranceBRDF",
    "StrokeSlopes",
    "PointSourceBRDF",
    "fresnel_real",
]

# --- issue 3: seed 003 diffuse-paint models -------------------------------------------
from .diffuse_subsurface import DiffuseSubsurfaceBRDF  # noqa: E402
from .facet_btdf import FacetBTDF  # noqa: E402
from .phase import HenyeyGreenstein  # noqa: E402
from .single_scatter import SingleScatterBRDF  # noqa: E402

__all__ += ["HenyeyGreenstein", "SingleScatterBRDF", "DiffuseSubsurfaceBRDF", "FacetBTDF"]
from .rough_diffuse import RoughDiffuseBRDF  # noqa: E402

__all__ += ["RoughDiffuseBRDF"]
from .combination import mueller_with_error  # noqa: E402

__all__ += ["mueller_with_error"]
from .maxwell_beard import MaxwellBeardBRDF  # noqa: E402

__all__ += ["MaxwellBeardBRDF"]
from .aperture import DetectorAperture  # noqa: E402

__all__ += ["DetectorAperture"]

# --- issue 15: Smith shadowing-masking and thin-film stacks ----------------------------
from . import shadowing  # noqa: E402
from .thin_film import FilmStack, TabulatedIndex  # noqa: E402

__all__ += ["shadowing", "FilmStack", "TabulatedIndex"]
