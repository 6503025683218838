"""
Seed 000 Table I beside the paper
=================================

The 27 integrated reflectances of Table I (Germer and Marx): aluminium flakes,
silicon and a perfect conductor under coatings of index 1.0, 1.5 and 2.0, with
exponential slopes of rms slope 0, 0.1 and 0.2, at 60 deg incidence. Each entry
is :func:`scatterbench.validation.integrated_reflectance` of
:class:`scatterbench.models.SubsurfaceFacetBRDF` (the flat column is the closed form), computed
by the same function the Table I check and ``scatterbench table1`` use, and set
beside the printed value and an independent calculation (SCATMECH's model
integrated over facet slopes, or the model's own integral at sigma = 1e-3).
"""

import matplotlib.pyplot as plt
import numpy as np

from scatterbench.validation.checks import table1

rows, seconds = table1.compute_table1()
print(table1.format_table1(rows))
print(f"27 entries in {seconds:.2f} s")

# %%
# Computed against printed, entry by entry. The error bars are the printed
# rounding (0.005); the five entries outside it are the ones the independent
# calculations contradict (see the guide's page on the papers' slips).
printed = np.array([r.printed for r in rows])
computed = np.array([r.computed for r in rows])
ok = np.array([r.within_rounding for r in rows])
fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
ax.plot([0, 1], [0, 1], "k:", lw=0.8)
ax.plot(printed[ok], computed[ok], "o", label="within the printed rounding")
ax.plot(printed[~ok], computed[~ok], "s", color="C3", label="outside (independent calculation agrees)")
ax.set_xlabel("Table I, printed")
ax.set_ylabel("scatterbench")
ax.legend(fontsize=8)
k = np.arange(len(rows))
bx.errorbar(k, computed - printed, yerr=0.005, fmt="none", ecolor="0.7")
bx.plot(k[ok], (computed - printed)[ok], "o")
bx.plot(k[~ok], (computed - printed)[~ok], "s", color="C3")
bx.axhline(0, color="k", lw=0.6)
bx.set_xlabel("entry")
bx.set_ylabel("scatterbench - printed")
fig.tight_layout()
plt.show()
