"""The model interface: one evaluation path for one geometry or millions.

Every BRDF/BTDF model is a frozen dataclass of declared parameters
(:mod:`models.params`) deriving from :class:`Model`.  A model implements
``_mueller16(theta_i, theta_r, phi_r)`` on flat float64 arrays and returns the
16 Mueller elements as a ``(16, n)`` array; :class:`Model` validates and
broadcasts the user's angles, evaluates them in cache-sized chunks (so memory
stays bounded and numpy's temporaries stay in cache) and returns
``broadcast_shape + (4, 4)``.  Non-depolarizing models also implement
``_jones_flat``.

Models combine incoherently with arithmetic, as in ``astropy.modeling``:
``m1 + m2`` and ``0.3 * m`` give a :class:`Sum`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .geometry import broadcast_angles
from .params import Declared, check_finite_array, check_polar_angle, param
from .polarization import ellipsometric, stokes

__all__ = ["Model", "Sum", "CHUNK"]

#: Geometries evaluated per chunk, chosen so a model's float64 temporaries stay in
#: L2 cache (measured best of 1024..32768 for the facet models on this machine).
CHUNK = 4096


class Model(Declared):
    """Base class of every scattering model (BRDF in 1/sr).

    Subclasses set ``depolarizing`` (True when no Jones matrix exists),
    ``reciprocal`` (True when Helmholtz reciprocity must hold) and
    ``transmission`` (True for a BTDF, whose second polar angle is measured from
    -z).
    """

    depolarizing = False
    reciprocal = True
    transmission = False
    #: True when M00 is even in phi_r (mirror plane of incidence); integrators use it.
    mirror_symmetric = True
    #: angle names used in error messages
    _angle_names = ("theta_i", "theta_r", "phi_r")
    #: every public model class, in definition order (for listings and sweeps)
    registry: list = []

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if not cls.__name__.startswith("_") and cls.__module__.startswith("models"):
            Model.registry.append(cls)

    # -- subclass hooks -----------------------------------------------------------
    def _mueller16(self, ti, tr, pr):  # pragma: no cover - abstract
        raise NotImplementedError

    def _jones_flat(self, ti, tr, pr):
        raise NotImplementedError(f"{type(self).__name__} is depolarizing: it has no Jones matrix")

    # -- validation and chunked evaluation ----------------------------------------
    def _angles(self, theta_i, theta_r, phi_r):
        n1, n2, n3 = self._angle_names
        ti = check_polar_angle(n1, theta_i)
        tr = check_polar_angle(n2, theta_r)
        pr = check_finite_array(n3, phi_r)
        return broadcast_angles(ti, tr, pr)

    def _chunks(self, theta_i, theta_r, phi_r):
        """Validate the angles; return ``(shape, n, blocks)`` where ``blocks`` yields
        ``(slice, ti, tr, pr)`` flat chunks of the broadcast geometries.

        The broadcast arrays are never materialized: inputs of the full shape are
        sliced, scalars are filled per chunk and other broadcast inputs are
        gathered per chunk, so a (1000, 1) x (1, 10^4) scan uses chunk-sized
        memory, not 10^7-sized inputs.
        """
        n1, n2, n3 = self._angle_names
        arrays = [
            check_polar_angle(n1, theta_i),
            check_polar_angle(n2, theta_r),
            check_finite_array(n3, phi_r),
        ]
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        n = math.prod(shape)
        flat = [a.reshape(-1) if a.shape == shape else None for a in arrays]

        def blocks():
            for start in range(0, n, CHUNK):
                stop = min(start + CHUNK, n)
                idx = None
                parts = []
                for a, f in zip(arrays, flat, strict=True):
                    if f is not None:
                        parts.append(f[start:stop])
                    elif a.size == 1:
                        parts.append(np.full(stop - start, a.reshape(-1)[0]))
                    else:
                        if idx is None:
                            idx = np.unravel_index(np.arange(start, stop), shape)
                        parts.append(np.broadcast_to(a, shape)[idx])
                yield (slice(start, stop), *parts)

        return shape, n, blocks()

    def iter_mueller(self, theta_i, theta_r, phi_r=0.0):
        """Stream the Mueller BRDF: yields ``(flat_slice, block)`` with ``block`` of shape
        ``(k, 4, 4)`` for consecutive runs of the C-ordered broadcast geometries.

        Memory stays bounded by the chunk size however many geometries there are
        (10^7 and beyond): reduce or store each block as it comes.
        """
        _, _, blocks = self._chunks(theta_i, theta_r, phi_r)
        for sl, ti, tr, pr in blocks:
            yield sl, self._mueller16(ti, tr, pr).T.reshape(-1, 4, 4)

    def mueller(self, theta_i, theta_r, phi_r=0.0, out=None):
        """Mueller-matrix BRDF ``(..., 4, 4)`` in 1/sr, s/p bases (SCATMECH ``psps``).

        ``out``, optional: a ``(16, N)`` float64 array (e.g. a ``numpy.memmap``)
        to write into, element-major, for very large evaluations.
        """
        shape, n, blocks = self._chunks(theta_i, theta_r, phi_r)
        # Element-major storage: each chunk's (16, k) block is copied without a
        # transpose; the (..., 4, 4) result is a strided view of it.
        if out is None:
            out = np.empty((16, n))
        elif out.shape != (16, n):
            raise ValueError(f"out must have shape (16, {n}); got {out.shape}")
        for sl, ti, tr, pr in blocks:
            out[:, sl] = self._mueller16(ti, tr, pr)
        return np.moveaxis(out.reshape((4, 4) + shape), (0, 1), (-2, -1))

    def brdf(self, theta_i, theta_r, phi_r=0.0):
        """Unpolarized-in, total-out BRDF ``M00`` (1/sr)."""
        shape, n, blocks = self._chunks(theta_i, theta_r, phi_r)
        out = np.empty(n)
        for sl, ti, tr, pr in blocks:
            out[sl] = self._brdf_flat(ti, tr, pr)
        return out.reshape(shape)

    def _brdf_flat(self, ti, tr, pr):
        return self._mueller16(ti, tr, pr)[0]

    def jones(self, theta_i, theta_r, phi_r=0.0):
        """Jones matrix ``(..., 2, 2)`` acting on ``(E_s, E_p)``, normalized so that its
        Mueller matrix is the Mueller BRDF (units sr^-1/2).  Only for
        non-depolarizing models; the overall phase is arbitrary."""
        if self.depolarizing:
            raise NotImplementedError(f"{type(self).__name__} is depolarizing: it has no Jones matrix")
        shape, n, blocks = self._chunks(theta_i, theta_r, phi_r)
        out = np.empty((n, 2, 2), dtype=complex)
        for sl, ti, tr, pr in blocks:
            out[sl] = self._jones_flat(ti, tr, pr)
        return out.reshape(shape + (2, 2))

    def scattered_stokes(self, theta_i, theta_r, phi_r=0.0, incident="unpolarized"):
        """Scattered Stokes vector BRDF ``(..., 4)`` for an incident state (name or vector)."""
        s_in = stokes(incident)
        return self.mueller(theta_i, theta_r, phi_r) @ s_in

    def polarization(self, theta_i, theta_r, phi_r=0.0, incident="unpolarized"):
        """``dict(brdf, eta, P_C, P)`` of the scattered light (seed 000 Sec. 3)."""
        s_in = np.asarray(stokes(incident))
        i, eta, pc, p = ellipsometric(self.scattered_stokes(theta_i, theta_r, phi_r, s_in))
        return {"brdf": i / s_in[0], "eta": eta, "P_C": pc, "P": p}

    def rotated(self, angle):
        """The model of the sample rotated by ``angle`` about z.  Models with no
        preferred azimuth (isotropic slopes, smooth interfaces) return themselves:
        callers test ``model.rotated(a) is model`` to take their isotropic paths."""
        return self

    def _rotated_slopes(self, angle):
        """:meth:`rotated` for a model whose only azimuthal structure is its ``slopes``."""
        slopes = self.slopes.rotated(angle)
        return self if slopes is self.slopes else self.replace(slopes=slopes)

    # -- integration hints -------------------------------------------------------------
    def lobe(self, theta_i):
        """``(theta_center, phi_center, width)`` of a narrow lobe, or ``None``.

        Integrators use it to put points where the model is sharply peaked.
        """
        return None

    # -- composition -----------------------------------------------------------------
    def __add__(self, other):
        if not isinstance(other, Model):
            return NotImplemented
        return Sum(terms=tuple(_terms(self) + _terms(other)))

    def __mul__(self, w):
        if isinstance(w, Model):
            return NotImplemented
        return Sum(terms=tuple((float(w) * k, m) for k, m in _terms(self)))

    __rmul__ = __mul__

    @classmethod
    def info(cls) -> str:
        """Docstring summary and declared parameters, for listing models."""
        head = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else cls.__name__
        lines = [f"{cls.__name__}: {head}"]
        for p in cls.parameters():
            old = f"; old name{'s' if len(p.aliases) > 1 else ''} {', '.join(p.aliases)}" if p.aliases else ""
            default = f"{'(required)':<22}" if p.required else f"default={p.default!r:<14}"
            lines.append(f"    {p.name:<12} {default} {p.doc} ({p.range_text()}{old})")
        return "\n".join(lines)


def _terms(m):
    if isinstance(m, Sum):
        return list(m.terms)
    return [(1.0, m)]


@dataclass(frozen=True)
class Sum(Model):
    """Incoherent, weighted sum of models: ``M = sum_k w_k M_k``.

    Built by ``m1 + m2`` and ``w * m``.  Depolarizing in general (a sum of
    Jones-derived Mueller matrices need not be one), reciprocal when every term
    is.
    """

    terms: tuple = param((), "tuple of (weight, model) pairs", kind="object")

    depolarizing = True

    def _validate(self):
        if not self.terms:
            raise ValueError("terms must hold at least one (weight, model) pair")
        clean = []
        for item in self.terms:
            if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[1], Model)):
                raise ValueError("terms must be (weight, model) pairs with a Model instance")
            w = float(item[0])
            if not math.isfinite(w) or w < 0:
                raise ValueError(f"weight must be a finite real >= 0; got {item[0]!r}")
            clean.append((w, item[1]))
        object.__setattr__(self, "terms", tuple(clean))
        if any(m.transmission != self.terms[0][1].transmission for _, m in self.terms):
            raise ValueError("terms must all be BRDFs or all BTDFs")

    @property
    def transmission(self):  # type: ignore[override]
        return self.terms[0][1].transmission

    @property
    def reciprocal(self):  # type: ignore[override]
        return all(m.reciprocal for _, m in self.terms)

    @property
    def mirror_symmetric(self):  # type: ignore[override]
        return all(m.mirror_symmetric for _, m in self.terms)

    def _mueller16(self, ti, tr, pr):
        total = None
        for w, m in self.terms:
            block = w * m._mueller16(ti, tr, pr)
            total = block if total is None else total + block
        return total

    def lobe(self, theta_i):
        lobes = [m.lobe(theta_i) for _, m in self.terms]
        lobes = [lb for lb in lobes if lb is not None]
        if not lobes:
            return None
        return min(lobes, key=lambda lb: lb[2])

    def rotated(self, angle):
        terms = tuple((w, m.rotated(angle)) for w, m in self.terms)
        return (
            self
            if all(r is m for (_, r), (_, m) in zip(terms, self.terms, strict=True))
            else Sum(terms=terms)
        )

    def __repr__(self):
        return " + ".join(f"{w:g}*{m!r}" for w, m in self.terms)


class _Wrapper(Model):
    """A model that changes how another reflection model (its ``model`` field) is
    illuminated or observed (point source, detector aperture): the inner model must
    be a reflection model, and mirror symmetry and rotations of the sample follow it.
    Depolarizing (its result is a weighted sum of the inner model's matrices) and not
    reciprocal (the source or the detector alone is changed)."""

    depolarizing = True
    reciprocal = False

    def _validate(self):
        if not isinstance(self.model, Model) or self.model.transmission:
            raise ValueError(f"model must be a reflection model (models.Model); got {self.model!r}")

    @property
    def mirror_symmetric(self) -> bool:
        return bool(self.model.mirror_symmetric)

    def rotated(self, angle):
        inner = self.model.rotated(angle)
        return self if inner is self.model else self.replace(model=inner)
