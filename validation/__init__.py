"""scatterbench validation: integrators, physics checks, comparisons, reports, CLI.

``validation`` may import ``models``; ``models`` never imports ``validation``.
"""

from .numerics.integrate import IntegralResult, integrated_reflectance
from .numerics.reciprocity import ReciprocityResult, reciprocity_error

__all__ = ["IntegralResult", "integrated_reflectance", "ReciprocityResult", "reciprocity_error"]
