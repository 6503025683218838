"""Thin-film colour travel (issue 15): spectra of film stacks and their sRGB colour, with the
CIE 1931 colour-matching functions and D65 of colour-science."""

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from scatterbench import models, references
from scatterbench.models import scene
from scatterbench.validation.studies import colour as C

WL = C.WAVELENGTHS_NM


def test_zero_thickness_film_is_a_neutral_grey():
    stack = models.FilmStack(layers=((2.6, 0.0),), substrate=1.58, wavelength_nm=550.0)
    refl = C.film_reflectance(stack, np.array([1.0, 0.8]), WL, 1.0)
    # the bare mica interface: ((1.58 - 1) / 2.58)^2 at normal incidence, at every wavelength
    assert np.allclose(refl[0], ((1.58 - 1) / 2.58) ** 2, rtol=1e-12, atol=0)
    rgb = C.srgb(WL, refl)
    # grey: equal channels, up to the difference between colour-science's D65 spectrum
    # integrated at 5 nm (its chromaticity) and the sRGB white point (measured: channel spread
    # 9e-5 for white, 1.6e-4 of the value for this grey after sRGB's gamma encoding)
    assert np.all(np.ptp(rgb, axis=-1) <= 2e-4 * rgb.max(axis=-1))
    assert np.all(rgb > 0.1) and np.all(rgb < 0.5)


def test_quarter_wave_tio2_at_550_nm_looks_green():
    stack = models.FilmStack(layers=((2.6, 550.0 / (4 * 2.6)),), substrate=1.58, wavelength_nm=550.0)
    refl = C.film_reflectance(stack, np.array(1.0), WL, 1.0)
    assert WL[np.argmax(refl)] == 550.0  # the interference maximum is at the design wavelength
    dominant = C.dominant_wavelength(WL, refl)
    rgb = C.srgb(WL, refl)
    assert 495.0 < dominant < 570.0, dominant  # the CIE hue name for 495-570 nm is green
    assert np.argmax(rgb) == 1, rgb  # and sRGB's largest channel is G


def test_pearlescent_scene_colour_travel():
    sc = scene.load(references.scene_path("pearlescent_mica_tio2.toml"))
    model = sc.mechanisms()[0].model
    t = C.colour_travel(model, sc.theta_i)
    assert t.reflectance.shape == (len(C.ASPECULAR_DEG), len(WL)) and t.srgb.shape == (
        len(C.ASPECULAR_DEG),
        3,
    )
    assert np.all((t.reflectance > 0) & (t.reflectance < 1))
    # the local angle on the reflecting flakes falls from near specular toward the normal
    assert t.local_deg[0] > t.local_deg[3] > t.local_deg[4]
    # in the plane of incidence the spectrum is w_s R_s + w_p R_p of the stack at the local
    # angle, normalized: between the two polarizations' reflectances
    k = 3
    cos_a = math.cos(math.radians(t.local_deg[k]))
    rs, rp = (
        np.array([q[0] for q in pair])
        for pair in zip(
            *[model.substrate.at(w).reflectance_transmittance(np.array([cos_a]), 1.5)[:2] for w in WL],
            strict=True,
        )
    )
    assert np.all(t.reflectance[k] >= np.minimum(rs, rp) - 1e-15)
    assert np.all(t.reflectance[k] <= np.maximum(rs, rp) + 1e-15)
    with pytest.raises(ValueError, match="FilmStack"):
        C.colour_travel(models.FacetBRDF(), 0.5)
    with pytest.raises(ValueError, match="below the surface"):
        C.colour_travel(model, sc.theta_i, aspecular_deg=(140.0,))


def test_import_models_does_not_load_colour_science():
    code = (
        "import sys, scatterbench.models, scatterbench.validation.studies.colour; "
        "assert 'colour' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True, env=dict(os.environ))
