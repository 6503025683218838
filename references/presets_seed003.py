"""Paper presets of seed 003 (Germer, diffuse paints): the samples of Fig. 2 and 3.

Data with provenance; :func:`build` turns a preset into a model.  Numbers not
printed in the paper are marked ``"printed": False`` with the reason; they are
our choices, there so that the preset can be evaluated, not the paper's fit.
"""

from __future__ import annotations

__all__ = ["PRESETS", "build", "names"]

PRESETS = {
    "glossy_white": {
        "sample": "glossy white paint",
        "wavelength_nm": 632.8,
        "figure": "Fig. 2 (left), solid curve",
        "model": "DiffuseSubsurfaceBRDF",
        "params": {"n": 1.5, "rho": 0.93},
        "printed": True,
        "source": "Sec. 4: 'n was approximately 1.5 and ... rho was set to 0.93'; theta_i = 60 deg (Sec. 3).",
        "theta_i_deg": 60.0,
    },
    "red_paint": {
        "sample": "glossy red pigmented paint",
        "wavelength_nm": 441.6,
        "figure": "Fig. 2 (right), solid curve (combination)",
        "model": "FacetBRDF + SingleScatterBRDF + DiffuseSubsurfaceBRDF (incoherent sum)",
        "params": {
            "n": 1.5,
            "sigma": 0.05,
            "slopes": "GaussianSlopes",
            "g": 0.3,
            "rho": 0.1,
            "w_facet": 1.0,
            "w_single": 1.0,
            "w_diffuse": 1.0,
        },
        "printed": False,
        "source": "Sec. 4: 'hand-fitted with an incoherent combination of the reflective facet scattering "
        "model, the single volume scattering model, and the totally diffuse volume scattering model'; "
        "no parameter values are printed.  n = 1.5 as for the paper's other binders; sigma, g, rho "
        "and the weights are our placeholders (a glossy surface, a low reflectance at 442 nm).",
        "theta_i_deg": 60.0,
    },
    "green_carc": {
        "sample": "green chemical agent resistant coating (CARC)",
        "wavelength_nm": 632.8,
        "figure": "Fig. 3, solid curve (Monte Carlo)",
        "model": "RoughDiffuseBRDF",
        "params": {
            "n": 1.5,
            "sigma": 2.0,
            "slopes": "ExponentialSlopes",
            "g": 0.3,
            "rho": 0.05,
            "pairs": 5000,
        },
        "printed": True,
        "source": "Sec. 4: 'index of the binder ... 1.5', 'exponential in slope with a rms slope of 2', "
        "'g-factor ... 0.3', 'rho ... 0.05', no shadowing; 5000 pairs for a smooth curve (Sec. 2.5); "
        "polarized phase function (Eq. 7); surface facet term included (Sec. 2.5).",
        "theta_i_deg": 60.0,
    },
}


def names():
    return sorted(PRESETS)


def build(name, seed=0):
    """The model of a preset (imports :mod:`models` lazily: references holds data)."""
    import models

    if name not in PRESETS:
        raise ValueError(f"name must be one of {', '.join(names())}; got {name!r}")
    p = PRESETS[name]["params"]
    if name == "glossy_white":
        return models.DiffuseSubsurfaceBRDF(n=p["n"], rho=p["rho"])
    slopes = getattr(models, p["slopes"])(sigma=p["sigma"])
    phase = models.HenyeyGreenstein(g=p["g"], polarized=True)
    if name == "green_carc":
        return models.RoughDiffuseBRDF(
            slopes=slopes, n=p["n"], phase=phase, rho=p["rho"], pairs=p["pairs"], seed=seed, surface=True
        )
    return (
        p["w_facet"] * models.FacetBRDF(slopes=slopes, substrate=p["n"])
        + p["w_single"] * models.SingleScatterBRDF(n=p["n"], phase=phase)
        + p["w_diffuse"] * models.DiffuseSubsurfaceBRDF(n=p["n"], rho=p["rho"])
    )
