"""Single volume scattering beneath a smooth interface (seed 003 Sec. 2.2, Eq. 8-20).

A ray refracts into a half-space of real index ``n`` (the ``coating``: the binder
around the scatterers), scatters once with the
phase function of :mod:`scatterbench.models.phase` at a depth with the exponential
probability of Eq. 16-19, and refracts out.  The Mueller BRDF (Eq. 20) is

    f = P(k_i', k_r') (x) [diag(t_r) J diag(t_i)] * cos ti' cos tr' / (cos ti cos tr (cos ti' + cos tr'))

where the first factor is the phase matrix in the internal rays' bases.  The
Jones matrix of Eq. 12-13 is evaluated directly from the dyadics in the
repository's bases (``s = unit(z x k)``, ``p = k x s``, SCATMECH's;
seed 003 Eq. 8 writes ``s = k x n``, the opposite sign for both ``s`` and ``p``
of every ray, which leaves Jones matrices unchanged).  With the projection
dyadic of Eq. 4 the internal Jones elements are ``e_a(out') . e_b(in')``:

    ss = cos(phi_r),  ps = -sin(phi_r) cos(ti'),  sp = -sin(phi_r) cos(tr'),
    pp = sin(ti') sin(tr') - cos(ti') cos(tr') cos(phi_r).

Printed Eq. 13 has the opposite sign on ``q_ps`` and on the ``cos cos cos``
term of ``q_pp``; those signs do not follow from Eq. 12 in either basis
(``q_ps`` and ``q_sp`` must have the same sign for ``M = D M^T D``, Helmholtz
reciprocity, which the tests check).  With the depolarizing phase
only ``|t|^2`` enter and the model is SCATMECH's ``First_Diffuse_BRDF_Model``
(with ``Unpolarized_Phase_Function``, no absorption), which it matches to
1e-12.  The ``cos'/cos`` factors are carried by the amplitudes of
:func:`scatterbench.models.smooth_interface.interface_amplitudes`, so grazing geometries give
exact zeros.

Films on the interface (``coating_films``: ambient | films | binder).  The amplitudes
``t_r``, ``t_i`` of Eq. 20 become the stack's complex crossing amplitudes, ``t_01`` in and
``t_10 kz_0 / kz_s`` out (:mod:`scatterbench.models.smooth_interface`, F1-F2; with the ``sqrt(cos'/cos)``
factor, :func:`scatterbench.models.smooth_interface.film_amplitudes`).  The Jones elements above become
complex products ``a_out,a J_ab a_in,b`` (the films' s/p phase difference reaches the
polarized model's U and V rows); the depolarizing phase sees only ``|a|^2``, the stack's
transmittances over ``n`` (F3).  Directions, the phase function and the depth integral
(Eq. 16-19) are the bare interface's: planar films bend no ray.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Model
from .constraints import Instance
from .facts import Correspondence, scatmech_index
from .params import coating_param, param
from .phase import HenyeyGreenstein
from .polarization import mueller16_from_jones
from .smooth_interface import depolarized_between, film_amplitudes, interface_amplitudes, squared_modulus
from .thin_film import FilmedCoating, Films, coating_films_param

__all__ = ["SingleScatterBRDF"]


@dataclass(frozen=True)
class SingleScatterBRDF(FilmedCoating, Model):
    """Single scattering by a volume diffuser beneath a smooth interface (seed 003 Eq. 20).

    SCATMECH: ``First_Diffuse_BRDF_Model`` (depolarizing phase function only).

    Parameters
    ----------
    coating : float
        Real index ``n`` of the binder around the scatterers, the medium light enters
        through the smooth interface (``1``: no interface).  Old name ``n``.
    phase : HenyeyGreenstein
        Phase function (polarized Eq. 7 or depolarizing).
    coating_films : Films or None
        Thin films on the interface (:class:`scatterbench.models.Films`, from the ambient down), on the
        index ``coating``; ``None`` (default): the bare interface of seed 003.
    """

    coating: float = coating_param(
        1.5, "index n of the binder around the scatterers, entered through the smooth interface (real)"
    )
    phase: HenyeyGreenstein = param(
        HenyeyGreenstein(0.3),
        "volume phase function",
        Instance(HenyeyGreenstein, text="a models.HenyeyGreenstein"),
    )
    coating_films: Films = coating_films_param("thin films on the smooth interface (None: bare)")

    aliases = {"n": "coating"}
    correspondence = Correspondence(
        "seed 003 Eq. 2-20",
        "``First_Diffuse_BRDF_Model`` (``Unpolarized_Phase_Function``; depolarizing phase only)",
    )

    @property
    def scatmech(self):
        """SCATMECH's ``First_Diffuse_BRDF_Model`` with its ``Unpolarized_Phase_Function`` of a
        Henyey-Greenstein phase (no absorption), or ``None``: current SCATMECH has no
        polarized (Rayleigh-Gans) phase function, and no films here."""
        sub, g = scatmech_index(self.coating), self.phase.g
        if sub is None or self.phase.polarized or self.coating_films is not None or not isinstance(g, float):
            return None
        return "First_Diffuse_BRDF_Model", {
            "substrate": sub,
            "phase_function": "Unpolarized_Phase_Function",
            "phase_function.phase_function": "Henyey_Greenstein_Phase_Function",
            "phase_function.phase_function.g": g,
            "phase_function.log_absorption": -1000,
        }

    @property
    def depolarizing(self):  # type: ignore[override]
        return not self.phase.polarized

    def _parts(self, ti, tr, pr):
        """Internal geometry, the amplitude factors (complex through films) and the scalar
        weight ``K``."""
        cos_ext = np.cos(np.stack([ti, tr]))
        if self._top_stack is None:
            (si, sr), (ci, cr), (asi, asr), (api, apr) = interface_amplitudes(cos_ext, self.coating)
        else:
            # in at theta_i, out at theta_r
            (si, sr), (ci, cr), (asi, api), (asr, apr) = film_amplitudes(cos_ext, self._top_stack)
        cp, sp = np.cos(pr), np.sin(pr)
        cos_scat = si * sr * cp - ci * cr  # k_i' . k_r'
        # Eq. 19-20: p4 / cos(tr) with the solid-angle factor, cos'/cos carried by the amplitudes.
        K = self.phase.density(cos_scat) / np.maximum(ci + cr, 1e-300)
        return si, sr, ci, cr, cp, sp, cos_scat, asi, asr, api, apr, K

    def _jones_parts(self, ti, tr, pr):
        si, sr, ci, cr, cp, sp, cos_scat, asi, asr, api, apr, K = self._parts(ti, tr, pr)
        root = np.sqrt(2.0 * K / (1.0 + cos_scat * cos_scat))  # Eq. 6-7 normalization
        ss = asr * asi * root * cp
        ps = -(asr * api * root) * sp * ci
        sp_ = -(apr * asi * root) * sp * cr
        pp = apr * api * root * (si * sr - ci * cr * cp)
        if self._top_stack is not None:  # complex amplitudes through the films
            return tuple((z.real, z.imag) for z in (ss, ps, sp_, pp))
        zero = 0.0  # real Jones matrix: a scalar imaginary part saves array work in the map
        return (ss, zero), (ps, zero), (sp_, zero), (pp, zero)

    def _mueller16(self, ti, tr, pr):
        if self.phase.polarized:
            return mueller16_from_jones(*self._jones_parts(ti, tr, pr))
        _, _, _, _, _, _, _, asi, asr, api, apr, K = self._parts(ti, tr, pr)
        return depolarized_between(asi, api, asr, apr, K)  # a depolarizing phase between the crossings

    def _kernel_spec(self):
        if self.coating_films is not None:
            return None  # films: numpy
        return "single", [self.coating, self.phase.g], (int(self.phase.polarized), 0, 0)

    def _brdf_flat(self, ti, tr, pr):
        if self.phase.polarized:
            # M00 of the Jones matrix: the product form below holds for the depolarizing phase
            # only (with s and p transmitted differently the polarized phase weighs them apart)
            return 0.5 * sum(re * re + im * im for re, im in self._jones_parts(ti, tr, pr))
        _, _, _, _, _, _, _, asi, asr, api, apr, K = self._parts(ti, tr, pr)
        q = squared_modulus
        return 0.25 * K * (q(asr) + q(apr)) * (q(asi) + q(api))

    def _jones_flat(self, ti, tr, pr):
        if not self.phase.polarized:
            return Model._jones_flat(self, ti, tr, pr)
        parts = self._jones_parts(ti, tr, pr)
        J = np.empty(ti.shape + (4,), dtype=complex)
        for k, (re, im) in enumerate(parts):
            J[:, k] = re
            J[:, k].imag = im
        return J.reshape(ti.shape + (2, 2))

    def lobe(self, theta_i):
        """Forward-peaked phase functions (g -> 1) scatter into a lobe around the
        refracted-forward direction, which exits at grazing: no narrow lobe inside
        the hemisphere for the integrator to find.  None."""
        return None
