"""scatterbench models: polarized light scattering by coated, flake-pigmented,
rough and diffuse surfaces (seeds 000, 001, 003; conventions in DESIGN.md).

Angles are radians; results broadcast and have shape ``broadcast + (4, 4)``.
"""

# isort: off
# Model.registry lists the model classes in the order they are defined, which is the
# order of these imports: seed 000, seed 001, seed 003, the detector aperture, then the
# measured-data expansion (NIST's PTFE).
from .base import CHUNK, Model, Sum
from .evaluation import backend
from .facet import FacetBRDF
from .subsurface_facet import SubsurfaceFacetBRDF
from .cook_torrance import CookTorranceBRDF, fresnel_real
from .point_source import PointSourceBRDF, point_source_geometry
from .stroke_slopes import StrokeSlopes
from .varnished import VarnishedCookTorranceBRDF
from .diffuse_subsurface import DiffuseSubsurfaceBRDF
from .facet_btdf import FacetBTDF
from .phase import HenyeyGreenstein
from .single_scatter import SingleScatterBRDF
from .rough_diffuse import RoughDiffuseBRDF
from .rough_subsurface import RoughSubsurfaceBRDF
from .combination import mueller_with_error
from .maxwell_beard import MaxwellBeardBRDF
from .aperture import DetectorAperture
from .zernike import ZernikeExpansionBRDF

# isort: on
from . import shadowing
from .fresnel import fresnel_coefficients, fresnel_reflectance, fresnel_transmittance
from .params import ParamInfo
from .polarization import (
    basis_rotation,
    ellipsometric,
    is_physical,
    jones_to_mueller,
    psps_to_xyxy,
    reciprocal_jones,
    reciprocal_mueller,
    stokes,
    xyxy_to_psps,
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
    UnitSlopes,
)
from .thin_film import Films, FilmStack, TabulatedIndex

__all__ = [
    "backend",
    "shadowing",
    "FilmStack",
    "Films",
    "TabulatedIndex",
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
    "UnitSlopes",
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
    "CookTorranceBRDF",
    "VarnishedCookTorranceBRDF",
    "StrokeSlopes",
    "PointSourceBRDF",
    "point_source_geometry",
    "fresnel_real",
    "HenyeyGreenstein",
    "SingleScatterBRDF",
    "DiffuseSubsurfaceBRDF",
    "FacetBTDF",
    "RoughDiffuseBRDF",
    "RoughSubsurfaceBRDF",
    "mueller_with_error",
    "MaxwellBeardBRDF",
    "DetectorAperture",
    "ZernikeExpansionBRDF",
    "basis_rotation",
    "xyxy_to_psps",
    "psps_to_xyxy",
    "list_models",
]


def list_models():
    """Names and parameter listings of every model class (like SCATMECH's model lists)."""
    return "\n\n".join(c.info() for c in Model.registry)
