"""Thin-film colour travel: the specular spectrum of flakes with films, and its sRGB colour.

In a facet model the light reaching a viewer at a given geometry was reflected by the
facets whose normal bisects the two (refracted) directions, at the local incidence angle
``alpha`` of that geometry.  In the plane of incidence that facet's normal lies in the
plane too, so the s and p of the rays are the facet's: for unpolarized light the BRDF is
a wavelength-independent factor times ``w_s R_s + w_p R_p``, with ``w`` the coating's
transmission (``|t_in t_out|^2``, seed 000 Eq. 14-15) and ``R`` the stack's reflectances
at ``alpha`` seen from the coating.  Divided by the same model with a perfect-mirror
substrate (``R_s = R_p = 1``), it is a reflectance in [0, 1]: the colour seen at that
aspecular angle, whose travel with angle is the interference pigment's "flop".
:func:`colour_travel` computes it for a :class:`scatterbench.models.FacetBRDF` or
:class:`scatterbench.models.SubsurfaceFacetBRDF` whose substrate is a :class:`scatterbench.models.FilmStack`
(evaluated at each wavelength with :meth:`scatterbench.models.FilmStack.at`, so dispersive indices,
callables of the wavelength, are followed); :func:`film_reflectance` is the stack's own
``(R_s + R_p) / 2``.

Colour: CIE 1931 2-degree colour-matching functions and the D65 illuminant from
``colour-science`` (not typed in), XYZ of the reflectance under D65 normalized so a
perfect white has ``Y = 1``, then sRGB (IEC 61966-2-1, D65 white, gamma-encoded), clipped
to [0, 1].  ``colour`` is imported only here, when called.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scatterbench import models

__all__ = [
    "ColourTravel",
    "film_reflectance",
    "srgb",
    "dominant_wavelength",
    "colour_travel",
    "ASPECULAR_DEG",
]

#: multi-angle colour geometries of the paint industry (ASTM E2539: aspecular angles, deg)
ASPECULAR_DEG = (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0)
#: the visible range of the colour-matching functions used here, 5 nm steps
WAVELENGTHS_NM = np.arange(380.0, 781.0, 5.0)


@dataclass(frozen=True)
class ColourTravel:
    """Spectra and colours of a film-stack facet model versus aspecular angle.

    ``reflectance[k, j]`` is the BRDF relative to a perfect-mirror substrate's (module
    docstring) at ``aspecular_deg[k]`` (the reflecting facets' local angle ``local_deg[k]`` in
    the coating) and ``wavelengths_nm[j]``; ``srgb[k]``
    its colour, ``dominant_nm[k]`` its dominant wavelength (negative: complementary, a
    purple)."""

    theta_i_deg: float
    aspecular_deg: tuple
    local_deg: tuple
    wavelengths_nm: np.ndarray
    reflectance: np.ndarray
    srgb: np.ndarray
    dominant_nm: tuple


def film_reflectance(stack, cos_local, wavelengths_nm=WAVELENGTHS_NM, n_incident=1.0):
    """``(R_s + R_p) / 2`` of ``stack`` at local incidence cosines ``cos_local`` (any shape)
    and each wavelength: shape ``cos_local.shape + (len(wavelengths_nm),)``."""
    c = np.asarray(cos_local, dtype=float)
    out = np.empty(c.shape + (len(wavelengths_nm),))
    for j, wl in enumerate(wavelengths_nm):
        rs, rp, _, _ = stack.at(float(wl)).reflectance_transmittance(c, n_incident)
        out[..., j] = 0.5 * (rs + rp)
    return out


def _cmfs_d65(wavelengths_nm):
    """``(xbar, ybar, zbar)`` rows and D65 at ``wavelengths_nm`` (colour-science data)."""
    import colour  # colour-science (heavy, optional): loaded only for thin-film colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    xyz_bar = np.array([cmfs[float(w)] for w in wavelengths_nm])  # (n, 3)
    return xyz_bar, np.array([d65[float(w)] for w in wavelengths_nm])


def _xyz(wavelengths_nm, reflectance):
    """CIE XYZ under D65 (``Y = 1`` for a perfect white) of reflectance spectra ``(..., n)``."""
    bar, d65 = _cmfs_d65(wavelengths_nm)
    weights = bar * d65[:, None]  # equal wavelength steps: the sums are the integrals
    return np.asarray(reflectance) @ weights / weights[:, 1].sum()


def srgb(wavelengths_nm, reflectance):
    """Gamma-encoded sRGB in [0, 1] (clipped) of reflectance spectra ``(..., n)`` under D65."""
    import colour  # colour-science (heavy, optional): loaded only for thin-film colour

    rgb = colour.XYZ_to_sRGB(_xyz(wavelengths_nm, reflectance))
    return np.clip(rgb, 0.0, 1.0)


def dominant_wavelength(wavelengths_nm, reflectance):
    """Dominant wavelength (nm) of a reflectance spectrum under D65 (colour-science's, from
    the chromaticity and the D65 white point; negative for a complementary one)."""
    import colour  # colour-science (heavy, optional): loaded only for thin-film colour

    xy = colour.XYZ_to_xy(_xyz(wavelengths_nm, reflectance))
    white = colour.XYZ_to_xy(_xyz(wavelengths_nm, np.ones(len(wavelengths_nm))))
    wl, _, _ = colour.dominant_wavelength(xy, white)
    return float(wl)


def _model_reflectance(model, theta_i, tr, pr, wavelengths_nm):
    """The model's BRDF at the views ``(tr, pr)`` and each wavelength over the same model's
    with a perfect-mirror substrate (module docstring): shape ``(len(tr), len(wavelengths))``."""
    mirror = model.replace(substrate=math.inf).brdf(theta_i, tr, pr)
    out = np.empty((len(tr), len(wavelengths_nm)))
    for j, wl in enumerate(wavelengths_nm):
        out[:, j] = model.replace(substrate=model.substrate.at(float(wl))).brdf(theta_i, tr, pr) / mirror
    return out


def colour_travel(model, theta_i, aspecular_deg=ASPECULAR_DEG, wavelengths_nm=WAVELENGTHS_NM):
    """:class:`ColourTravel` of ``model`` (a facet model whose substrate is a
    :class:`scatterbench.models.FilmStack`) lit at ``theta_i`` (radians), seen in the plane of incidence at
    each aspecular angle (degrees; the view must stay above the surface)."""
    stack = getattr(model, "substrate", None)
    if not isinstance(stack, models.FilmStack):
        raise ValueError(f"model must be a facet model with a FilmStack substrate; got {model!r}")
    n = float(getattr(model, "coating", 1.0))
    aspecular = np.asarray(aspecular_deg, dtype=float).reshape(-1)
    # toward the incident side for positive values (the paint industry's convention)
    tr, pr = models.geometry.signed_inplane(theta_i - np.radians(aspecular))
    below = ~((tr >= 0.0) & (tr < 0.5 * math.pi))
    if below.any():
        a = float(aspecular[np.argmax(below)])
        raise ValueError(f"aspecular_deg {a!r} puts the view below the surface at theta_i = {theta_i!r}")
    cos_local = models.facet.local_cosine(np.full_like(tr, theta_i), tr, pr, n)
    wl = np.asarray(wavelengths_nm, dtype=float)
    refl = _model_reflectance(model, theta_i, tr, pr, wl)
    return ColourTravel(
        float(math.degrees(theta_i)),
        tuple(float(a) for a in aspecular),
        tuple(float(d) for d in np.degrees(np.arccos(np.minimum(cos_local, 1.0)))),
        wl,
        refl,
        srgb(wl, refl),
        tuple(dominant_wavelength(wl, r) for r in refl),
    )
