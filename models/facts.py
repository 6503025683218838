"""What each model class says about itself, beside its parameters.

:class:`ModelFacts` is a mixin of :class:`scatterbench.models.Model`; a model class overrides
what applies to it, so that adding a model means writing one class, not entries in tables
elsewhere keyed by its name:

* ``correspondence``: the paper equations and the SCATMECH and Mitsuba 3 models it
  corresponds to (:class:`Correspondence`; the docs show it on the class page and in the
  models table, and a class without one is a docs build warning);
* ``scatmech``: the equivalent SCATMECH model of *this instance*, ``(name, parameters)`` as
  SCATMECH strings, or ``None`` where SCATMECH has no equivalent of its options (the
  conformance kit's ``scatmech`` check compares with it);
* ``sweep_base()`` and ``sweep_extras()``: the stability sweep's representative instance
  and the further instances (with the parameters swept from them) its edges do not reach;
* ``kit_variant``: parameter changes from ``sweep_base()`` that give the conformance kit's
  instance (:func:`scatterbench.validation.testing.shipped_models`).

The stability sweep's edge values of each parameter are part of its declaration
(:func:`scatterbench.models.params.param`), and a slope distribution's kernel code is its
class's ``kernel_code``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

__all__ = ["Correspondence", "ModelFacts", "scatmech_index"]


@dataclass(frozen=True)
class Correspondence:
    """Where a model comes from and what implements it elsewhere (reST text; ``"—"``: none).

    ``paper``: the seed equations; ``scatmech``: the SCATMECH model (DESIGN.md, "Reference
    implementation: SCATMECH"); ``mitsuba``: the Mitsuba 3 plugin (DESIGN.md, "A second peer")."""

    paper: str
    scatmech: str = "—"
    mitsuba: str = "—"


class ModelFacts:
    """Defaults of the per-class facts (module docstring): none declared."""

    #: paper equations and peer models (``None``: undocumented, a docs build warning)
    correspondence: Correspondence | None = None
    #: the equivalent SCATMECH model of an instance (a property where one exists)
    scatmech = None
    #: changes to :meth:`sweep_base` for the conformance kit's instance (e.g. fewer Monte
    #: Carlo pairs testing the same code faster)
    kit_variant = MappingProxyType({})

    @classmethod
    def sweep_base(cls):
        """The stability sweep's representative instance (its defaults), or ``None`` for a
        composition without defaults (:class:`scatterbench.models.Sum`: its terms are swept)."""
        try:
            return cls()
        except ValueError:
            return None

    @classmethod
    def sweep_extras(cls) -> tuple:
        """``((instance, swept parameter names), ...)``: instances the edges of
        :meth:`sweep_base` do not reach, each swept at the edges of the parameters named
        (``()``: as it is)."""
        return ()


def scatmech_index(value):
    """A scalar index as SCATMECH's ``"(n,k)"`` string, or ``None`` where it has no such form
    (``math.inf``, a film stack, an array of a model set)."""
    if isinstance(value, (bool, np.ndarray)) or not isinstance(value, (int, float, complex)):
        return None
    z = complex(value)
    if not (math.isfinite(z.real) and math.isfinite(z.imag)):
        return None
    return f"({z.real!r},{z.imag!r})"
