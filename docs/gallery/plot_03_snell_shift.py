"""
Seed 003 Fig. 1: the Snell shift of facet transmission
======================================================

The in-plane BTDF of :class:`scatterbench.models.FacetBTDF` (Gaussian slopes, n = 1.5) at
60 deg incidence peaks near the Snell angle for narrow slope distributions and
moves toward the incident direction as they widen; the BTDF-weighted mean
transmitted angle follows ``sin(theta_t) = sin(theta_i) / n_eff`` with an
effective index below n. The peak and ``n_eff`` are computed by the functions of
the Fig. 1 check (:mod:`scatterbench.validation.checks.fig1`), for three of its sigmas.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

from scatterbench import models
from scatterbench.models.geometry import signed_inplane
from scatterbench.validation.checks.fig1 import N_INDEX, THETA_I, effective_index, peak_angle

sigmas = (0.05, 0.3, 1.0)
snell = math.degrees(math.asin(math.sin(THETA_I) / N_INDEX))
x = np.linspace(-89.0, 89.0, 357)
tt, pt = signed_inplane(np.radians(x))
fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
for sigma in sigmas:
    m = models.FacetBTDF(slopes=models.GaussianSlopes(sigma=sigma), substrate=N_INDEX)
    f = m.brdf(THETA_I, tt, pt)
    n_eff, residual = effective_index(sigma)
    peak = peak_angle(sigma)
    print(f"sigma = {sigma:g}: peak {peak:.3f} deg (Snell {snell:.3f}), n_eff = {n_eff:.4f}")
    (line,) = ax.plot(x, f / f.max(), label=f"sigma = {sigma:g}, peak {peak:.2f} deg")
    s_in = np.linspace(0.0, math.sin(math.radians(80)), 20)
    bx.plot(s_in, s_in / n_eff, color=line.get_color(), label=f"n_eff = {n_eff:.3f}")
ax.axvline(snell, color="k", ls=":", lw=0.8)
ax.set_xlim(-20, 89)
ax.set_xlabel("signed theta_t (deg, + forward)")
ax.set_ylabel("BTDF / peak")
ax.legend(fontsize=7)
bx.plot([0, 1], [0, 1 / N_INDEX], "k:", label=f"Snell, n = {N_INDEX:g}")
bx.set_xlabel("sin(theta_i)")
bx.set_ylabel("sin(mean theta_t)")
bx.legend(fontsize=7)
fig.tight_layout()
plt.show()
