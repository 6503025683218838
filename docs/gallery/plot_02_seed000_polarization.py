"""
Seed 000 Fig. 2 and Fig. 3: BRDF and polarization of coated flakes
==================================================================

Aluminium flakes (``1.37+7.62i``) with exponential slopes under coatings of
index 1.0, 1.5 and 2.0, at 60 deg incidence
(:class:`scatterbench.models.SubsurfaceFacetBRDF`). Fig. 2: the in-plane BRDF for unpolarized
light. Fig. 3: the principal angle eta, the degree of polarization P and of
circular polarization P_C for light polarized at 45 deg, for the coated flakes
and for an exposed rough polymer (:class:`scatterbench.models.FacetBRDF`, n = 1.5). The
curves and the figures are the report section's
(:func:`scatterbench.validation.report.sections.seed000.compute`, quick: 179 in-plane angles;
:func:`~scatterbench.validation.report.sections.seed000.draw_fig2`, :func:`~scatterbench.validation.report.sections.seed000.draw_fig3`).
"""

import matplotlib.pyplot as plt

from scatterbench.validation.report.core import Context
from scatterbench.validation.report.sections import seed000

d = seed000.compute(Context(quick=True))
fig = seed000.draw_fig2(d)

# %%
# Fig. 3: polarization of the scattered light for 45 deg linear incident light.
fig = seed000.draw_fig3(d)
plt.show()
