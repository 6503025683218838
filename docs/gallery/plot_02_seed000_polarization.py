"""
Seed 000 Fig. 2 and Fig. 3: BRDF and polarization of coated flakes
==================================================================

Aluminium flakes (``1.37+7.62i``) with exponential slopes under coatings of
index 1.0, 1.5 and 2.0, at 60 deg incidence
(:class:`models.SubsurfaceFacetBRDF`). Fig. 2: the in-plane BRDF for unpolarized
light. Fig. 3: the principal angle eta, the degree of polarization P and of
circular polarization P_C for light polarized at 45 deg, for the coated flakes
and for an exposed rough polymer (:class:`models.FacetBRDF`, n = 1.5).
"""

import math

import matplotlib.pyplot as plt
import numpy as np

import models
from models.geometry import signed_inplane

AL = 1.37 + 7.62j
ti = math.radians(60)
x = np.linspace(-89, 89, 179)  # signed in-plane angle, negative: the incidence side
tr, pr = signed_inplane(np.radians(x))

fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for ax, sigma in zip(axes, (0.1, 0.2), strict=True):
    for n, style in ((1.0, "-"), (1.5, "--"), (2.0, ":")):
        m = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(sigma), coating=n, substrate=AL)
        ax.semilogy(x, np.maximum(m.brdf(ti, tr, pr), 1e-10), style, label=f"coating n = {n:g}")
    ax.set_title(f"Fig. 2: sigma = {sigma:g}")
    ax.set_xlabel("theta_r (deg, signed)")
    ax.legend(fontsize=8)
axes[0].set_ylabel("BRDF (1/sr)")
fig.tight_layout()

# %%
# Fig. 3: polarization of the scattered light for 45 deg linear incident light.
coated = models.SubsurfaceFacetBRDF(slopes=models.ExponentialSlopes(0.2), coating=1.5, substrate=AL)
polymer = models.FacetBRDF(slopes=models.ExponentialSlopes(0.2), substrate=1.5)
fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
for model, label, style in ((coated, "aluminium under n = 1.5", "-"), (polymer, "exposed polymer", "--")):
    p = model.polarization(ti, tr, pr, incident="linear:45")
    axes[0].plot(x, np.degrees(p["eta"]), style, label=label)
    axes[1].plot(x, p["P"], style)
    axes[2].plot(x, p["P_C"], style)
for ax, name in zip(axes, ("eta (deg)", "P", "P_C"), strict=True):
    ax.set_ylabel(name)
axes[0].legend(fontsize=8)
axes[2].set_xlabel("theta_r (deg, signed)")
fig.tight_layout()
plt.show()
