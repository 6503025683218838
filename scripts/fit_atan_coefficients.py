"""The coefficients of :func:`scatterbench.models.kernels.vector_math.atan2`'s polynomial, derived.

    pip install mpmath && python scripts/fit_atan_coefficients.py

Fits ``f(z) = (atan u - u) / u^3``, ``z = u^2``, on ``[0, tan^2(pi/8)]`` (the range the
reduction leaves) by a Chebyshev series in 50-digit arithmetic (``mpmath.chebyfit``), and
prints the fit's largest error for 8 to 13 coefficients and the 11 kept, constant term
first, as ``vector_math`` writes them.  The error enters ``atan u`` multiplied by
``z <= 0.172``: with 11 coefficients 3.2e-17 becomes 5e-18, a twentieth of an ulp.
"""

import mpmath as mp

mp.mp.dps = 50
Z = mp.tan(mp.pi / 8) ** 2
KEPT = 11


def f(z):
    if z == 0:
        return mp.mpf(-1) / 3
    u = mp.sqrt(z)
    return (mp.atan(u) - u) / u**3


for n in range(8, 14):
    print(f"{n} coefficients: largest error {mp.nstr(mp.chebyfit(f, [0, Z], n, error=True)[1], 3)}")
poly = mp.chebyfit(f, [0, Z], KEPT)  # highest degree first
print(", ".join(repr(float(c)) for c in reversed(poly)))
