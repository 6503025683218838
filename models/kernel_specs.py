"""What the compiled kernels cover, without importing them: the codes of slope
distributions and shadowing, and a model's parameters laid out as kernel rows.

A model's ``_kernel_spec`` (see :class:`scatterbench.models.Model`) returns ``(code, rows, options)``
built with these helpers, or ``None`` where the kernels do not cover it; then the numpy
implementation runs.  Not covered (numpy): tabulated slopes and the angle distributions
(their normalizations are quadratures), Smith shadowing of distributions without a
closed-form ``Lambda`` (the exponential families use a tabulated one), film-stack
substrates, ``FacetBTDF(convention="corrected")`` (its projected area is an average over
quantiles), and the Monte Carlo and wrapper models (whose inner models use the kernels).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SLOPE_CODES", "SHADOWING_KINDS", "slope_rows", "index_rows", "shadowing_kind", "named_rows"]

# The slope kinds the kernels know (models.kernels.common uses the same numbers); each slope
# distribution class names its own as ``kernel_code`` (models.slopes).
EXPONENTIAL, GAUSSIAN, GGX, ANISO_EXPONENTIAL, ANISO_GAUSSIAN, ANISO_GGX, STROKE, UNIT = range(8)
#: every slope code the kernels know
SLOPE_CODES = (EXPONENTIAL, GAUSSIAN, GGX, ANISO_EXPONENTIAL, ANISO_GAUSSIAN, ANISO_GGX, STROKE, UNIT)
#: slope kinds whose Smith Lambda has a closed form in the kernels
SMITH_KINDS = (GAUSSIAN, GGX, ANISO_GAUSSIAN, ANISO_GGX)
SHADOWING_KINDS = {"none": 0, "smith": 1, "smith-correlated": 2}
#: the Cook-Torrance kernel's shadowing codes (Smith's ``G`` of its Gaussian slopes)
COOK_SHADOWING = {"none": 0, "blinn": 1, "smith": 2}
#: in a vector loop's option set, an option the loop reads at run time
#: (:func:`scatterbench.models.kernels.vector.lane_options`)
RUNTIME = -1


#: each kernel's parameter rows, by name and in order: a model's ``_kernel_spec`` gives its
#: rows in this order, the kernels read them by position, and :class:`scatterbench.models.kernels.Compiled`
#: checks a spec against them (names only here: no numba)
FACET_ROWS = ("coating", "substrate_re", "substrate_im", "sx", "sy", "rotation", "coverage")
BTDF_ROWS = ("substrate", "sx", "sy", "rotation", "coverage")
SINGLE_ROWS = ("coating", "g")
DIFFUSE_ROWS = ("coating", "scale")
#: varnish index (1: bare), metal index, Eq. 19's m values and stroke azimuth, and the stroke
#: azimuth's cosine and sine, taken once per model (no C library call per geometry: the
#: Cook-Torrance loop runs on SIMD lanes)
COOK_ROWS = ("coating", "substrate_re", "substrate_im", "m_parallel", "m_perpendicular", "stroke_angle")
COOK_ROWS += ("stroke_cos", "stroke_sin")
#: the facet kernel's rows, then rho_d, rho_v, tau, omega
MAXWELL_ROWS = FACET_ROWS + ("rho_d", "rho_v", "tau", "omega")
KERNEL_ROWS = {
    "facet": FACET_ROWS,
    "btdf": BTDF_ROWS,
    "single": SINGLE_ROWS,
    "diffuse": DIFFUSE_ROWS,
    "cook": COOK_ROWS,
    "maxwell": MAXWELL_ROWS,
}


def slope_rows(slopes):
    """``(kind, [sx, sy, rotation, coverage])`` of a slope distribution (its class's
    ``kernel_code`` and ``kernel_row()``), or ``None`` where no kernel evaluates it."""
    kind = getattr(slopes, "kernel_code", None)
    if kind is None:
        return None
    return kind, slopes.kernel_row()


def shadowing_kind(shadowing, kind):
    """The kernels' code of ``shadowing`` for slopes of ``kind``, or ``None`` (numpy)."""
    if shadowing != "none" and kind not in SMITH_KINDS:
        return None
    return SHADOWING_KINDS[shadowing]


def index_rows(index):
    """``[re, im]`` of a refractive index (``math.inf``: ``[inf, 0]``; arrays element-wise)."""
    if isinstance(index, np.ndarray):
        return [index.real, index.imag]
    if index == math.inf:
        return [math.inf, 0.0]
    z = complex(index)
    return [z.real, z.imag]


def named_rows(model):
    """``(code, rows, options)`` of a model a kernel covers (``model._kernel_spec()`` not
    ``None``), ``rows`` by name (:data:`KERNEL_ROWS`), each broadcast over a model set's
    elements and flat: what the float32 domain and the kernels' tolerance are derived from."""
    code, rows, options = model._kernel_spec()
    values = np.broadcast_arrays(*(np.asarray(r, dtype=float) for r in rows))
    return code, {name: v.reshape(-1) for name, v in zip(KERNEL_ROWS[code], values, strict=True)}, options
