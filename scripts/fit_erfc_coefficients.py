"""The coefficients of :func:`scatterbench.models.kernels.vector_math.erfc`'s polynomial, derived.

    pip install mpmath && python scripts/fit_erfc_coefficients.py

``erfc x = exp(-x^2) f(t) / (1 + 2 x)`` for ``x >= 0``, with ``t = (x - K) / (x + K)``, ``K = 4``
(the transformation of Shepherd and Laframboise, Math. Comp. 36, 249 (1981), which maps
``[0, inf)`` onto ``[-1, 1)`` and leaves ``f = (1 + 2 x) exp(x^2) erfc x`` smooth, between 1 and
``2 / sqrt(pi)``).  Fits ``f`` on ``x`` in ``[0, XMAX]`` (beyond it ``erfc`` is below the normal
range) by a Chebyshev series in 40-digit arithmetic (``mpmath.chebyfit``), prints the fit's
largest error for 20 to 26 coefficients and the largest error of the kept polynomial evaluated
by Horner's rule in float64 (in units of the float64 epsilon), then the kept coefficients,
constant term first, as ``vector_math`` writes them.  Then, with scatterbench installed, the
largest error of :func:`scatterbench.models.kernels.vector_math.erfc` itself in ulp of the exact
value, on 2000 points of ``[-6, 27]`` and 500 from ``4e-18`` to 1 (seed 1), where ``erfc`` is
above 1e-300.
"""

import mpmath as mp
import numpy as np

mp.mp.dps = 40
K = mp.mpf(4)
XMAX = mp.mpf(27)
KEPT = 24
T_HI = (XMAX - K) / (XMAX + K)


def f(t):
    x = K * (1 + t) / (1 - t)
    return (1 + 2 * x) * mp.erfc(x) * mp.exp(x * x)


for n in range(20, 27, 2):
    print(f"{n} coefficients: largest error {mp.nstr(mp.chebyfit(f, [-1, T_HI], n, error=True)[1], 3)}")
poly = mp.chebyfit(f, [-1, T_HI], KEPT)  # highest degree first
coeffs = [float(c) for c in poly]
ts = np.linspace(-1.0, float(T_HI), 2001)
horner = np.zeros_like(ts)
for c in coeffs:
    horner = horner * ts + c
exact = np.array([float(f(mp.mpf(float(t)))) for t in ts])
print(
    f"{KEPT} kept, Horner in float64: largest error {np.max(np.abs(horner - exact) / exact) / 2.0**-52:.2f} eps"
)
print(", ".join(repr(c) for c in reversed(coeffs)))

try:
    from numba import njit

    from scatterbench.models.kernels.vector_math import erfc
except ImportError as exc:
    raise SystemExit(f"the kernel's error not measured: {exc}") from None


@njit
def _each(x):
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = erfc(x[i])
    return out


rng = np.random.default_rng(1)
x = np.concatenate([rng.uniform(-6.0, 27.0, 2000), np.exp(rng.uniform(-40.0, 0.0, 500))])
exact = np.array([float(mp.erfc(mp.mpf(float(v)))) for v in x])
live = exact > 1e-300
ulps = np.abs(_each(x) - exact)[live] / np.spacing(exact[live])
print(f"vector_math.erfc against the exact value: largest error {ulps.max():.0f} ulp ({live.sum()} points)")
