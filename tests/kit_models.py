"""Models written outside scatterbench (numpy only) for the conformance kit's tests: a correct
Lambertian, and broken ones that each break one rule (tests/test_conformance.py)."""

import math

import numpy as np


class Lambertian:
    """A correct Lambertian: f = rho / pi, an ideal depolarizer."""

    def __init__(self, rho=0.8):
        self.rho = rho

    def brdf(self, theta_i, theta_r, phi_r):
        shape = np.broadcast_shapes(np.shape(theta_i), np.shape(theta_r), np.shape(phi_r))
        return np.full(shape, self.rho / math.pi)

    def mueller(self, theta_i, theta_r, phi_r):
        f = self.brdf(theta_i, theta_r, phi_r)
        M = np.zeros(f.shape + (4, 4))
        M[..., 0, 0] = f
        return M


class LambertianWithOut(Lambertian):
    """The Lambertian with models.Model's out= convention: a (16, N) element-major buffer."""

    def mueller(self, theta_i, theta_r, phi_r, out=None):
        M = super().mueller(theta_i, theta_r, phi_r)
        if out is None:
            return M
        n = M[..., 0, 0].size
        if out.shape != (16, n):
            raise ValueError(f"out must have shape (16, {n}); got {out.shape}")
        out[:] = np.moveaxis(M.reshape(n, 16), 0, 1)
        return np.moveaxis(out.reshape((4, 4) + M.shape[:-2]), (0, 1), (-2, -1))


class IgnoresOut(Lambertian):
    """Takes out= but never writes it (broken)."""

    def mueller(self, theta_i, theta_r, phi_r, out=None):
        if out is not None and out.shape[0] != 16:
            raise ValueError("out must have 16 rows")
        if out is not None and out.shape[1] != np.size(theta_i):
            raise ValueError("out must have one column per geometry")
        return super().mueller(theta_i, theta_r, phi_r)


class NonReciprocal(Lambertian):
    """f = (1 + cos theta_i) / (4 pi): brighter at normal incidence than at normal viewing
    (albedo at most 1/2, so only reciprocity breaks)."""

    def brdf(self, theta_i, theta_r, phi_r):
        ti = np.asarray(theta_i, dtype=float)  # float64 whatever the angles' dtype
        return (1.0 + np.cos(ti)) / (4.0 * math.pi) + 0.0 * super().brdf(theta_i, theta_r, phi_r)


class CreatesEnergy(Lambertian):
    """A Lambertian with rho = 1.2: it reflects more light than it receives."""

    def __init__(self):
        super().__init__(rho=1.2)


class NaNNearGrazing(Lambertian):
    """A horizon taper sqrt(1 - 1e-8 / cos^2) on both directions with no clamp: NaN within
    0.006 deg of grazing (symmetric, so reciprocity holds where it is finite)."""

    def brdf(self, theta_i, theta_r, phi_r):
        taper = [np.sqrt(1.0 - 1e-8 / np.cos(np.asarray(t, dtype=float)) ** 2) for t in (theta_i, theta_r)]
        return super().brdf(theta_i, theta_r, phi_r) * taper[0] * taper[1]


class Unrealizable(Lambertian):
    """A Lambertian with a 'polarizer' of diattenuation 0.6 that keeps M22 = M33 = M00: no
    sum of Jones matrices gives it (the coherency matrix has a negative eigenvalue)."""

    def mueller(self, theta_i, theta_r, phi_r):
        M = super().mueller(theta_i, theta_r, phi_r)
        f = M[..., 0, 0]
        M[..., 0, 1] = M[..., 1, 0] = 0.6 * f
        M[..., 1, 1] = M[..., 2, 2] = M[..., 3, 3] = f
        return M


class UnseededNoise(Lambertian):
    """A Monte Carlo Lambertian that declares a seed but draws from a fresh generator: the
    same seed gives different numbers."""

    seed = 0

    def brdf(self, theta_i, theta_r, phi_r):
        f = super().brdf(theta_i, theta_r, phi_r)
        return f * (1.0 + 1e-3 * np.random.default_rng().standard_normal(f.shape))


class BreaksBroadcasting(Lambertian):
    """Stacks its angles with np.stack: scalars and equal-shape arrays work, a scalar with
    an array or an outer product does not."""

    def brdf(self, theta_i, theta_r, phi_r):
        x = np.stack([np.asarray(theta_i, float), np.asarray(theta_r, float), np.asarray(phi_r, float)])
        return np.full(x.shape[1:], self.rho / math.pi)
