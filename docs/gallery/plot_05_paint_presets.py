"""
Seed 003: the paint presets beside Maxwell-Beard
================================================

Seed 003 models three paints (Sec. 4): a glossy white paint
(:class:`models.DiffuseSubsurfaceBRDF`), a glossy red pigmented paint (an
incoherent combination of facet reflection, single scattering and the totally
diffuse term) and a green CARC coating (:class:`models.RoughDiffuseBRDF`, Monte
Carlo under a rough interface). The presets are scene files listed by
:func:`references.seed003_presets`; each is built with :mod:`models.scene`. Beside
each, the empirical Maxwell-Beard BRDF (:class:`models.MaxwellBeardBRDF`) is
fitted to the preset's in-plane BRDF by the report's least-squares fit
(sigma, rho_d and rho_v free), at 60 deg incidence and 45 deg linear polarization.
The red paint's parameters are not printed in the paper: its preset carries
placeholders (the preset's provenance says which).
"""

import matplotlib.pyplot as plt
import numpy as np

import models
import references
from models import scene
from models.geometry import signed_inplane
from validation.report.sections.seed003_presets import fit_maxwell_beard

x = np.linspace(-85.0, 85.0, 69)
tr, pr = signed_inplane(np.radians(x))
fig, axes = plt.subplots(1, 3, figsize=(12, 3.8), sharey=True)
for ax, (name, preset) in zip(axes, references.seed003_presets().items(), strict=True):
    sc = scene.load(preset["scene"])
    model = sc.build()
    if name == "green_carc":
        model = model.replace(pairs=200, seed=0)  # quick: 200 facet pairs per geometry
    M, E = models.mueller_with_error(model, sc.theta_i, tr, pr)
    rough = sc.coating.get("roughness")
    family = type(rough) if rough is not None else models.GaussianSlopes
    mb, par = fit_maxwell_beard(x, M[..., 0, 0], sc.theta_i, family, sc.coating["index"])
    print(
        f"{name}: Maxwell-Beard sigma {par['sigma']:.3f}, rho_d {par['rho_d']:.4f}, "
        f"rho_v {par['rho_v']:.4f}, rms log10 misfit {par['rms_log10']:.3f}"
    )
    ax.semilogy(x, M[..., 0, 0], label=f"preset ({preset['model'].split(' (')[0]})")
    if np.any(E[..., 0, 0] > 0):
        se = E[..., 0, 0]
        ax.fill_between(x, np.maximum(M[..., 0, 0] - 2 * se, 1e-12), M[..., 0, 0] + 2 * se, alpha=0.3, lw=0)
    ax.semilogy(x, mb.brdf(sc.theta_i, tr, pr), "--", label="Maxwell-Beard (fitted)")
    ax.set_title(preset["sample"], fontsize=9)
    ax.set_xlabel("signed theta_r (deg)")
    ax.legend(fontsize=7)
axes[0].set_ylabel("M00 (1/sr)")
fig.tight_layout()
plt.show()
