"""
Seed 001: published versus energy-normalized Cook-Torrance, and the point source
================================================================================

Eq. 7-8 of Hébert, Emmel and Hersch have no ``1/pi`` in D and no 4 in the
denominator: the published BRDF is exactly 4 pi times the energy-normalized
one, so its albedo exceeds 1. :class:`scatterbench.models.CookTorranceBRDF` keeps both
(``convention="paper"`` and ``"corrected"``). The published albedos are the seed 001
check's (:func:`scatterbench.validation.checks.seed001.published_albedos`), the energy-normalized
ones the report section's (:func:`scatterbench.validation.report.sections.seed001.ct_albedo_rows`),
for the paper's iron plate (m = 0.03, iron ``2.29+3.37i``, Blinn shadowing).
"""

import matplotlib.pyplot as plt
import numpy as np

from scatterbench import references
from scatterbench.validation.checks.seed001 import (
    iron_plate_models,
    point_source_collimated_error,
    published_albedos,
)
from scatterbench.validation.report.sections.seed001 import ct_albedo_rows, point_source_scan

published = published_albedos()
rows = ct_albedo_rows(published)  # the report section's table: the energy-normalized albedos beside them
energy = {r["theta_i (deg)"]: r["energy albedo"] for r in rows}
for r in rows:
    print(
        f"theta_i = {r['theta_i (deg)']:g} deg: published albedo {r['published albedo']:.4f}, "
        f"energy {r['energy albedo']:.4f}, ratio/(4 pi) {r['ratio / (4 pi)']:.6f}"
    )

fig, ax = plt.subplots(figsize=(6, 3.5))
ts = list(published)
ax.plot(ts, [published[t] for t in ts], "o-", label="published (Eq. 7-8 as printed)")
ax.plot(ts, [energy[t] for t in ts], "s-", label="energy-normalized")
ax.axhline(1.0, color="k", lw=0.6, ls=":")
ax.set_yscale("log")
ax.set_xlabel("theta_i (deg)")
ax.set_ylabel("albedo")
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# The point-source effect. The iron plate under a point source whose disc
# spans the printed incidence range (:func:`scatterbench.models.point_source_geometry`),
# in-plane, beside the collimated BRDF (:class:`scatterbench.models.PointSourceBRDF`, the
# exact superposition of Eq. 28; the report section's scan,
# :func:`scatterbench.validation.report.sections.seed001.point_source_scan`).
_, varnished = iron_plate_models()  # references.IRON_PLATE under its varnish, as printed
lo, hi = references.IRON_PLATE["incidence_ranges_deg"][0]
scan, _ = point_source_scan(varnished, lo, hi)  # the report section's scan
fig, ax = plt.subplots(figsize=(6, 3.5))
ax.semilogy(scan.theta_r_deg, scan.collimated, label="collimated")
ax.semilogy(scan.theta_r_deg, np.maximum(scan.point, 1e-6), "--", label=f"point source, d/R = {scan.d:.1f}")
ax.set_title(f"incidence range [{lo:g}, {hi:g}] deg")
ax.set_xlabel("theta_r in plane (deg)")
ax.set_ylabel("BRDF (1/sr)")
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# As the source recedes the point-source BRDF converges to the collimated one
# (the seed 001 check's measurement).
for dist, err in point_source_collimated_error(distances=(10.0, 100.0, 1000.0)).items():
    print(f"d/R = {dist:g}: max |f_point - f_collimated| / max f = {err:.3e}")
plt.show()
