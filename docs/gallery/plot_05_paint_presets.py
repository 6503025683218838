"""
Seed 003: the paint presets beside Maxwell-Beard
================================================

Seed 003 models three paints (Sec. 4): a glossy white paint
(:class:`scatterbench.models.DiffuseSubsurfaceBRDF`), a glossy red pigmented paint (an
incoherent combination of facet reflection, single scattering and the totally
diffuse term) and a green CARC coating (:class:`scatterbench.models.RoughDiffuseBRDF`, Monte
Carlo under a rough interface). The presets are scene files listed by
:func:`scatterbench.references.seed003_presets`; each is built with :mod:`scatterbench.models.scene`. Beside
each, the empirical Maxwell-Beard BRDF (:class:`scatterbench.models.MaxwellBeardBRDF`) is
fitted by least squares in log10 to the preset's in-plane BRDF for unpolarized
light (M00) at its incidence, 60 deg (sigma, rho_d and rho_v free). The curves,
the fits and the figure are the report section's
(:func:`scatterbench.validation.report.sections.seed003_presets.compute` and
:func:`~scatterbench.validation.report.sections.seed003_presets.draw`, quick: the green
CARC at 200 facet pairs per geometry); as there, the BRDF, the principal angle eta
and the degree of polarization P are drawn for incident light polarized at 45 deg (seed 003 Sec. 3), which in the plane of incidence
gives M00 where M02 vanishes (the printed max ``|M02|/M00`` says how nearly it
does). The red paint's parameters are not
printed in the paper: its preset carries placeholders (the preset's provenance
says which).
"""

import matplotlib.pyplot as plt

from scatterbench.validation.report.core import Context
from scatterbench.validation.report.sections import seed003_presets

d = seed003_presets.compute(Context(quick=True))
for row in d.fit_rows:
    print(
        f"{row['preset']}: Maxwell-Beard sigma {row['MB sigma']:.3f}, rho_d {row['MB rho_d (1/sr)']:.4f}, "
        f"rho_v {row['MB rho_v (1/sr)']:.4f}, rms log10 misfit {row['rms log10 misfit']:.3f}, "
        f"max |M02|/M00 in plane {row['max |M02|/M00 in plane']:.1e}"
    )

fig = seed003_presets.draw(d)
plt.show()
