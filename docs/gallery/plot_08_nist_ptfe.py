"""
NIST's sintered PTFE: measured Mueller BRDFs and the Zernike expansion
======================================================================

NIST's sintered PTFE measurements (T. A. Germer, Applied Optics 2017; a U.S. government work) are
read as published with :func:`scatterbench.validation.fitting.mueller_data.load_mueller_data`.
Each published coefficient table is evaluated with :class:`scatterbench.models.ZernikeExpansionBRDF`
at its rows' own geometries, in the data's xyxy basis. The tables below give the rms and max
residual of M11 (relative) and of each normalized element (absolute). They also give each
residual over the data's noise, estimated from second differences on the measurement grid
(:func:`scatterbench.validation.studies.measured_mueller.noise_level`). The same expansion turned
to psps misses the measured elements: the data are in xyxy. Below them come the properties of the
data themselves: reciprocity and mirror symmetry against the noise, and Cloude's realizability.
"""

import dataclasses

import matplotlib.pyplot as plt
import numpy as np

from scatterbench import models, references
from scatterbench.validation.fitting.mueller_data import ELEMENTS, load_mueller_data
from scatterbench.validation.studies import measured_mueller as mm

data = load_mueller_data(references.nist_ptfe_path())
noise = mm.noise_level(data)


def subset(name):
    return data if name == "all" else data.subset(data.wavelength_nm == float(name))


for name in ("351", "532", "633", "1064", "all"):
    z = models.ZernikeExpansionBRDF(coefficients=references.nist_ptfe_coefficients(name))
    r = mm.model_residuals(z, subset(name), noise)
    wrong = mm.model_residuals(z, dataclasses.replace(subset(name), basis="psps"), noise)
    print(
        f"table {name}: {r.n} rows, M11 rms {r.m11_rms:.4f} max {r.m11_max:.4f} (relative), chi2/dof {r.chi2:.2f}"
    )
    print("  normalized elements, rms / max (absolute):")
    for i in range(4):
        print(
            "   ",
            "  ".join(
                f"{ELEMENTS[4 * i + j]} {r.rms[i, j]:.4f}/{r.max[i, j]:.3f}" for j in range(4) if i or j
            ),
        )
    print(f"  the same expansion turned to psps against the xyxy data: chi2/dof {wrong.chi2:.2f}")

psps = data.in_basis("psps")
for label, pairs, relation in (
    ("reciprocity, strict pairs", mm.reciprocal_pairs(psps, isotropic=False), "reciprocity"),
    ("reciprocity, isotropic pairs", mm.reciprocal_pairs(psps), "reciprocity"),
    ("mirror symmetry", mm.mirror_pairs(psps), "mirror"),
):
    s = mm.pair_statistics(psps, pairs, relation, noise)
    print(
        f"{label}: {s.n} pairs, chi2/dof {s.chi2:.2f}, M11 rms {s.rms[0, 0]:.4f}, worst element ratio {s.ratio.max():.2f}"
    )
q = mm.realizability(data, noise)
print(
    f"realizability: {q.negative} of {q.n} matrices with a negative coherency eigenvalue, "
    f"{q.unphysical} beyond the noise; smallest eigenvalue {q.worst:.3f} M11"
)
for w, s in noise.items():
    print(f"noise at {w:g} nm: M11 {s[0]:.4f} (relative), normalized elements median {np.median(s[1:]):.4f}")

# In-plane cut at 532 nm: measured f_r11 and M22/M11 against the 532 nm table
sub = subset("532")
z = models.ZernikeExpansionBRDF(coefficients=references.nist_ptfe_coefficients("532"))
inplane = np.isclose(np.sin(sub.phi_r), 0.0, atol=1e-6)
fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
for k, ti in enumerate(np.unique(np.round(sub.theta_i, 6))):
    rows = inplane & np.isclose(sub.theta_i, ti)
    x = np.degrees(sub.theta_r[rows]) * np.where(np.cos(sub.phi_r[rows]) > 0, 1, -1)
    order = np.argsort(x)
    xs = np.linspace(-70, 70, 141)  # the measured range (0.9 = sin 64 deg on the grid), a little beyond
    M = z.mueller_general(ti, np.pi, np.radians(np.abs(xs)), np.where(xs >= 0, 0.0, np.pi), basis="xyxy")
    color = f"C{k}"
    ax.plot(x[order], sub.mueller[rows, 0, 0][order], "o", ms=3, color=color)
    ax.plot(xs, M[:, 0, 0], color=color, lw=1, label=f"theta_i = {np.degrees(ti):.0f} deg")
    bx.plot(x[order], sub.normalized()[rows, 1, 1][order], "o", ms=3, color=color)
    bx.plot(xs, M[:, 1, 1] / M[:, 0, 0], color=color, lw=1)
ax.set_xlabel("signed theta_r (deg, + specular side)")
ax.set_ylabel("f_r11 (1/sr)")
ax.legend(fontsize=7)
bx.set_xlabel("signed theta_r (deg, + specular side)")
bx.set_ylabel("M22 / M11")
fig.suptitle("NIST sintered PTFE, 532 nm, plane of incidence: measured (points), expansion (lines)")
fig.tight_layout()
plt.show()
