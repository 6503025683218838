"""Totally diffuse scattering beneath a smooth interface (seed 003 Sec. 2.3, Eq. 21-28).

A Lambertian, totally depolarizing reflector of reflectance ``rho`` sits under
a smooth interface of real index ``n`` (the ``coating``: the binder above the
diffuser); light diffusely reflected back by the
interface's underside returns to the diffuser (Eq. 23, geometric series with
the internal hemispherical reflectance ``R-bar``).  The Mueller BRDF (Eq. 27-28)
is

    f = (rho / pi) / (1 - rho R-bar) * cos ti' cos tr' / (cos ti cos tr) * M_diff

with ``M_diff`` built from ``|t|^2`` of both passes (four non-zero elements).
``R-bar`` uses the ``1/pi`` normalization (seed 003 Eq. 22 prints
``1/(2 pi)``; see :func:`scatterbench.models.smooth_interface.internal_hemispherical_reflectance`),
computed to ~1e-15 rather than with SCATMECH's 0.2-degree rectangle rule.  With
it, at ``rho = 1`` the specular reflectance plus the integrated diffuse BRDF is
exactly 1 (derivation: the diffuse term integrates to ``T(ti)``; tests check it
numerically).  SCATMECH: ``Diffuse_Subsurface_BRDF_Model``
(``reflectance.table = rho``).

Films on the interface (``coating_films``: ambient | films | binder).  Both crossings take
the stack's amplitudes (:mod:`scatterbench.models.smooth_interface`, F1-F3: ``n |a|^2`` is the stack's
transmittance in, and out), and ``R-bar`` is the stack's internal reflectance seen from
inside the binder, averaged with Eq. 22's ``1/pi`` (F5,
:func:`scatterbench.models.smooth_interface.film_hemispherical_reflectance`).  The unit-albedo argument
carries over for lossless films: at ``rho = 1`` the diffuse term integrates to the stack's
transmittance ``T_01(ti)``, so with its reflectance ``R_01(ti)`` the total is 1 (tested);
an absorbing film keeps it below 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .base import Model
from .constraints import Interval, ScalarOrArray
from .facts import Correspondence, scatmech_index
from .params import coating_param, param
from .smooth_interface import (
    depolarized_between,
    film_amplitudes,
    film_hemispherical_reflectance,
    interface_amplitudes,
    internal_hemispherical_reflectance,
    squared_modulus,
)
from .thin_film import FilmedCoating, Films, coating_films_param

__all__ = ["DiffuseSubsurfaceBRDF"]


@dataclass(frozen=True)
class DiffuseSubsurfaceBRDF(FilmedCoating, Model):
    """Lambertian diffuser under a smooth interface, multiple internal reflections (Eq. 27).

    Parameters
    ----------
    coating : float
        Real index ``n`` of the binder above the diffuser, the medium light enters through
        the smooth interface (``1``: a bare Lambertian).  Old name ``n``.
    rho : float
        Diffuse reflectance of the underlying material, in [0, 1].
    coating_films : Films or None
        Thin films on the interface (:class:`scatterbench.models.Films`, from the ambient down), on the
        index ``coating``; ``None`` (default): the bare interface of seed 003.
    """

    coating: float = coating_param(
        1.5, "index n of the binder above the diffuser, entered through the smooth interface (real)"
    )
    rho: float = param(
        0.93, "diffuse reflectance of the material under the interface", ScalarOrArray(Interval(0.0, 1.0))
    )
    coating_films: Films = coating_films_param("thin films on the smooth interface (None: bare)")

    depolarizing = True
    aliases = {"n": "coating"}
    correspondence = Correspondence(
        "seed 003 Eq. 21-28", "``Diffuse_Subsurface_BRDF_Model`` (``reflectance.table`` = rho)"
    )

    @property
    def scatmech(self):
        """SCATMECH's ``Diffuse_Subsurface_BRDF_Model`` (``substrate`` = coating,
        ``reflectance.table`` = rho), or ``None`` with films (it has none)."""
        sub = scatmech_index(self.coating)
        if sub is None or self.coating_films is not None or not isinstance(self.rho, float):
            return None
        return "Diffuse_Subsurface_BRDF_Model", {"substrate": sub, "reflectance.table": self.rho}

    @cached_property
    def rbar(self):
        """Internal hemispherical reflectance ``R-bar`` (Eq. 22 with 1/pi): a float, or an
        array like ``coating`` in a model set (the quadrature runs once per distinct index
        and is cached, :func:`scatterbench.models.smooth_interface.internal_hemispherical_reflectance`);
        through films, the stack's (:func:`scatterbench.models.smooth_interface.film_hemispherical_reflectance`)."""
        if self._top_stack is not None:
            return film_hemispherical_reflectance(self._top_stack)
        n = self.coating
        if isinstance(n, np.ndarray):
            values, inverse = np.unique(n, return_inverse=True)
            rbar = np.array([internal_hemispherical_reflectance(v) for v in values])
            return rbar[inverse.reshape(n.shape)]
        return internal_hemispherical_reflectance(n)

    @cached_property
    def _scale(self):
        """``(rho / pi) / (1 - rho R-bar)`` (Eq. 27's prefactor; arrays in a model set)."""
        return (self.rho / math.pi) / (1.0 - self.rho * self.rbar)

    def _kernel_spec(self):
        if self.coating_films is not None:
            return None  # films: numpy
        return "diffuse", [self.coating, self._scale], (0, 0, 0)

    def _amps(self, ti, tr):
        """Interface amplitudes ``(a_s, a_p)``, rows incidence then scattering (the exit's)."""
        cos_ext = np.cos(np.stack([ti, tr]))
        if self._top_stack is None:
            _, _, a_s, a_p = interface_amplitudes(cos_ext, self.coating)
            return a_s, a_p
        _, _, (a_s, a_p), (b_s, b_p) = film_amplitudes(cos_ext, self._top_stack)
        return np.stack([a_s, b_s]), np.stack([a_p, b_p])

    def _mueller16(self, ti, tr, pr):
        (asi, asr), (api, apr) = self._amps(ti, tr)
        return depolarized_between(asi, api, asr, apr, self._scale)

    def _brdf_flat(self, ti, tr, pr):
        a_s, a_p = self._amps(ti, tr)
        # (|t_s|^2 + |t_p|^2)/2 * cos'/cos, row i then row r
        S = 0.5 * (squared_modulus(a_s) + squared_modulus(a_p))
        return self._scale * S[1] * S[0]
