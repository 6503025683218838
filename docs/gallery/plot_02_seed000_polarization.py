"""
Seed 000 Fig. 2 and Fig. 3: BRDF and polarization of coated flakes
==================================================================

Aluminium flakes (``1.37+7.62i``) with exponential slopes under coatings of
index 1.0, 1.5 and 2.0, at 60 deg incidence
(:class:`models.SubsurfaceFacetBRDF`). Fig. 2: the in-plane BRDF for unpolarized
light. Fig. 3: the principal angle eta, the degree of polarization P and of
circular polarization P_C for light polarized at 45 deg, for the coated flakes
and for an exposed rough polymer (:class:`models.FacetBRDF`, n = 1.5). The
curves are the report section's
(:func:`validation.report.sections.seed000.compute`, quick: 179 in-plane angles).
"""

import matplotlib.pyplot as plt
import numpy as np

from validation.report.core import Context
from validation.report.sections import seed000

d = seed000.compute(Context(quick=True))

fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for ax, (sigma, curves) in zip(axes, d.fig2, strict=True):
    for (n, f), style in zip(curves, ("-", "--", ":"), strict=True):
        ax.semilogy(d.x, np.maximum(f, 1e-10), style, label=f"coating n = {n:g}")
    ax.set_title(f"Fig. 2: sigma = {sigma:g}")
    ax.set_xlabel("theta_r (deg, signed)")
    ax.legend(fontsize=8)
axes[0].set_ylabel("BRDF (1/sr)")
fig.tight_layout()

# %%
# Fig. 3: polarization of the scattered light for 45 deg linear incident light.
fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
for (label, eta, p, pc), style in zip(d.fig3, ("-", "--"), strict=True):
    axes[0].plot(d.x, eta, style, label=label)
    axes[1].plot(d.x, p, style)
    axes[2].plot(d.x, pc, style)
for ax, name in zip(axes, ("eta (deg)", "P", "P_C"), strict=True):
    ax.set_ylabel(name)
axes[0].legend(fontsize=8)
axes[2].set_xlabel("theta_r (deg, signed)")
fig.tight_layout()
plt.show()
