"""The model interface: one evaluation path for one geometry or millions.

Every BRDF/BTDF model is a frozen dataclass of declared parameters
(:mod:`scatterbench.models.params`) deriving from :class:`Model`.  A model implements
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
from functools import cached_property

import numpy as np

from . import evaluation, float32_domain, modelset
from .constraints import FACTOR_MAX, Instance, Interval
from .evaluation import CHUNK
from .facts import Correspondence, ModelFacts
from .geometry import broadcast_angles
from .modelset import array_leaves
from .params import Declared, param
from .polarization import ellipsometric, stokes

__all__ = ["Model", "Sum", "CHUNK", "is_isotropic"]


def is_isotropic(model) -> bool:
    """True when ``model`` has no preferred azimuth: :meth:`Model.rotated` returns the model
    itself (its documented contract), so a rotated sample need not be built."""
    return model.rotated(1.0) is model


def rotated_set(model, angles):
    """``model.rotated(angles)`` as one model set of ``angles``' shape (an array), or ``None``
    when the model's ``rotated`` takes a single angle only (a user's model may): callers then
    rotate angle by angle."""
    angles = np.asarray(angles, dtype=float)
    try:
        turned = model.rotated(angles)
        return turned if turned.param_shape == angles.shape else None
    except (TypeError, ValueError, AttributeError):
        return None


class Model(Declared, ModelFacts):
    """Base class of every scattering model (BRDF in 1/sr).

    Subclasses set ``depolarizing`` (True when no Jones matrix exists),
    ``reciprocal`` (True when Helmholtz reciprocity must hold) and
    ``transmission`` (True for a BTDF, whose second polar angle is measured from
    -z), and the facts of :class:`scatterbench.models.facts.ModelFacts` that apply to them.
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

    def __init_subclass__(cls, registry=True, **kwargs):
        """Public classes of :mod:`scatterbench.models` join :attr:`registry`; ``registry=False``
        keeps one out (a view of another object, :class:`scatterbench.models.contributed.Conformant`)."""
        super().__init_subclass__(**kwargs)
        public = not cls.__name__.startswith("_") and cls.__module__.startswith("scatterbench.models")
        if public and registry:
            Model.registry.append(cls)

    #: True when ``_mueller16``/``_brdf_flat`` take array parameters (flat, one per
    #: geometry); otherwise a model set's numpy path runs per distinct element
    _numpy_sets = False

    # -- subclass hooks -----------------------------------------------------------
    def _mueller16(self, ti, tr, pr):  # pragma: no cover - abstract
        raise NotImplementedError

    def _jones_flat(self, ti, tr, pr):
        raise NotImplementedError(f"{type(self).__name__} is depolarizing: it has no Jones matrix")

    def _kernel_spec(self):
        """``(code, parameters, options)`` for a compiled kernel (:mod:`scatterbench.models.kernels`), or
        ``None`` where no kernel covers this model and its options (then numpy)."""
        return None

    # -- model sets and dispatch ------------------------------------------------------
    def __post_init__(self):
        super().__post_init__()
        if self._sets:
            modelset.check_broadcast(self._sets)

    @cached_property
    def _sets(self) -> dict:
        """``{path: array}``: the parameters that are arrays (:mod:`scatterbench.models.modelset`)."""
        return array_leaves(self)

    @property
    def param_shape(self) -> tuple:
        """Broadcast shape of the array parameters (``()``: a single model, not a model set)."""
        return np.broadcast_shapes(*(a.shape for a in self._sets.values()))

    def with_values(self, values: dict, *, check: bool = True):
        """A model with parameters replaced by dotted paths (``{"slopes.sigma": array}``; tuple
        items by index, ``"terms.0.1.coating"``).  ``check=False`` trusts the values (a caller
        that range-checked them once, vectorized): no validation at all, so building a model
        set costs microseconds however many elements it holds."""
        leaves = {tuple(int(k) if k.isdigit() else k for k in p.split(".")): v for p, v in values.items()}
        if check:
            return modelset.rebuilt(self, leaves)
        return modelset.with_leaves(self, leaves)

    def _element(self, leaves, index):
        """The single model at ``index`` of flat array parameters (see :func:`evaluation.each`)."""
        return modelset.element(self, leaves, index)

    @cached_property
    def _kernel(self):
        spec = self._kernel_spec()
        if spec is None:
            return None
        from . import kernels  # numba (heavy): compiled kernels load when one first runs

        return kernels.Compiled(self, *spec)

    def flat_mueller16(self, ti, tr, pr):
        """The named internal entry for angles validated already: Mueller elements ``(16, n)``
        of flat float64 angles (length 1 or ``n``), by :func:`scatterbench.models.evaluation.flat`'s
        choice of kernel or numpy.  Wrappers, sums and fits evaluate their inner models
        through it; users call :meth:`mueller`, which validates and broadcasts."""
        return evaluation.flat(self, ti, tr, pr, 16)

    def indexed_kernel(self, index):
        """``(kernel, index)``: this model set's :class:`~scatterbench.models.kernels.Compiled`
        kernel over its flat parameters (length ``G``), one column per element, and ``index``
        checked against them (:meth:`~scatterbench.models.kernels.Compiled.indexed`), for
        :meth:`flat_mueller16_indexed` and for callers that evaluate ranges of the geometries
        themselves (a fit's likelihood, range by range through the cache); ``None`` where the
        set has no kernel (:func:`~scatterbench.models.evaluation.kernel_path`)."""
        if not evaluation.kernel_path(self):
            return None
        from . import kernels  # numba (heavy): compiled kernels load when one first runs

        code, rows, options = self._kernel_spec()
        g = math.prod(self.param_shape)
        # the rows once, one column per element (shared values repeated): the loops read column
        # index[k] in place (drive.column), where a gather per chunk built (11, chunk) arrays
        flat = [np.broadcast_to(np.asarray(r).reshape(-1) if np.size(r) == g else r, (g,)) for r in rows]
        kernel = kernels.Compiled(self, code, flat, options)
        return kernel, kernel.indexed(index)

    def flat_mueller16_indexed(self, index, ti, tr, pr, out, add=False):
        """Mueller elements ``(16, n)`` into ``out`` of this model set, whose parameters are flat
        (length ``G``), at flat float64 angles validated already (length 1 or ``n``), geometry
        ``k`` taking the set's element ``index[k]``: a fit's walkers x wavelengths, each shared by
        many rows.  What a model derives from its parameters (the kernel's rows: R-bar's
        quadrature, a validation) is computed once per element and gathered per geometry; the
        kernel rows are elementwise in the parameters, so the bits are those of the set
        broadcast to the geometries.  A model without a kernel here is that broadcast set
        through :func:`~scatterbench.models.evaluation.flat`.  ``add``: ``out +=`` the elements
        (a sum's later terms), the bits of adding them from an array of their own."""
        leaves = self._sets
        inplace = type(out) is np.ndarray and out.flags.c_contiguous and out.dtype == np.float64
        if add and not (inplace and evaluation.kernel_path(self)):
            out += self.flat_mueller16_indexed(index, ti, tr, pr, np.empty(out.shape))
            return out
        if not evaluation.kernel_path(self):
            whole = modelset.with_leaves(self, {p: a.reshape(-1)[index] for p, a in leaves.items()})
            out[...] = evaluation.flat(whole, ti, tr, pr)
            return out
        kernel, index = self.indexed_kernel(index)
        n = out.shape[1]
        if add:  # through cache-sized buffers (Compiled.accumulate)
            kernel.accumulate(ti, tr, pr, out, index)
            return out
        # in place, one call (the loops spread it over the cores); otherwise chunks bound write's buffer
        step = max(n if inplace else evaluation.KERNEL_CHUNK, 1)
        for start in range(0, n, step):
            sl = slice(start, min(start + step, n))
            angles = [a if a.shape[0] == 1 else a[sl] for a in (ti, tr, pr)]
            kernel.write(out, sl, *angles, "float64", index[sl])
        return out

    def flat_brdf(self, ti, tr, pr):
        """:meth:`flat_mueller16`'s ``M00`` ``(n,)`` alone."""
        return evaluation.flat(self, ti, tr, pr, 1)

    # -- the public evaluation: every route is chosen in models.evaluation --------------
    def _angles(self, theta_i, theta_r, phi_r):
        return broadcast_angles(*evaluation.checked_angles(self, theta_i, theta_r, phi_r))

    @cached_property
    def _has_kernel(self) -> bool:
        return self._kernel_spec() is not None

    def iter_mueller(self, theta_i, theta_r, phi_r=0.0):
        """Stream the Mueller BRDF: yields ``(flat_slice, block)`` with ``block`` of shape
        ``(k, 4, 4)`` for consecutive runs of the C-ordered broadcast geometries.

        Memory stays bounded by the chunk size however many geometries there are
        (10^7 and beyond): reduce or store each block as it comes.
        """
        return evaluation.blocks(self, theta_i, theta_r, phi_r)

    def mueller(self, theta_i, theta_r, phi_r=0.0, out=None, precision="float64"):
        """Mueller-matrix BRDF ``(..., 4, 4)`` in 1/sr, s/p bases (SCATMECH ``psps``).

        The angles broadcast against each other and against the parameter shape of a model
        set (:attr:`param_shape`).  ``out``, optional: a ``(16, N)`` array of the
        precision's dtype (e.g. a ``numpy.memmap``) to write into, element-major, for very
        large evaluations.  ``precision``: ``"float64"`` or ``"float32"``: the float32
        kernels (:mod:`scatterbench.models.kernels`) where the parameters lie in their float32-safe domain
        (:mod:`scatterbench.models.float32_domain`); otherwise, as for a model without a kernel, the
        float64 evaluation rounded to float32 (:attr:`float32_fallback` says why).
        """
        angles = (theta_i, theta_r, phi_r)
        fast = evaluation.small(self, theta_i, theta_r, phi_r, 16, precision, out)
        if fast is None:
            shape, out = evaluation.evaluate(self, theta_i, theta_r, phi_r, 16, precision, out)
            fast = evaluation.as_matrices(out, shape)
        return evaluation.finite32(self, fast, angles, 16, precision)

    def mueller16(self, theta_i, theta_r, phi_r=0.0, out=None, precision="float64"):
        """``(shape, M)``: the Mueller BRDF as its element-major storage ``M`` ``(16, N)``
        (row ``4 a + b`` is element ``ab``) and the broadcast ``shape`` of the geometries
        (``N`` their number); :meth:`mueller` returns a ``shape + (4, 4)`` view of it."""
        shape, m = evaluation.evaluate(self, theta_i, theta_r, phi_r, 16, precision, out)
        # the storage (16, N): rows of elements, refused or made finite as a whole
        evaluation.finite32(self, evaluation.as_matrices(m, shape), (theta_i, theta_r, phi_r), 16, precision)
        return shape, m

    def brdf(self, theta_i, theta_r, phi_r=0.0, precision="float64"):
        """Unpolarized-in, total-out BRDF ``M00`` (1/sr); ``precision`` as for :meth:`mueller`."""
        fast = evaluation.small(self, theta_i, theta_r, phi_r, 1, precision)
        if fast is None:
            shape, out = evaluation.evaluate(self, theta_i, theta_r, phi_r, 1, precision)
            fast = out.reshape(shape)
        return evaluation.finite32(self, fast, (theta_i, theta_r, phi_r), 1, precision)

    @property
    def float32_fallback(self) -> str | None:
        """Why ``precision="float32"`` evaluates this model in float64 and rounds the result
        (a sentence), or ``None`` when the float32 kernel evaluates it: no kernel covers the
        model or its options, the numpy backend is selected, or the parameters lie outside
        the float32-safe domain (:mod:`scatterbench.models.float32_domain`; decided once per model)."""
        if not self._has_kernel:
            return f"no compiled kernel covers {type(self).__name__} with these options"
        if evaluation.current_backend() != "numba":
            return "the numpy backend is selected (models.backend)"
        return self._float32_unsafe if evaluation.float32_guarded() else None

    @cached_property
    def _float32_unsafe(self):
        return float32_domain.model_unsafe(self)

    def _brdf_flat(self, ti, tr, pr):
        return self._mueller16(ti, tr, pr)[0]

    def jones(self, theta_i, theta_r, phi_r=0.0):
        """Jones matrix ``(..., 2, 2)`` acting on ``(E_s, E_p)``, normalized so that its
        Mueller matrix is the Mueller BRDF (units sr^-1/2).  Only for
        non-depolarizing models; the overall phase is arbitrary."""
        if self.depolarizing:
            raise NotImplementedError(f"{type(self).__name__} is depolarizing: it has no Jones matrix")
        return evaluation.jones(self, theta_i, theta_r, phi_r)

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
        callers test it (:func:`is_isotropic`) to take their isotropic paths."""
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
        w = WEIGHT.check("weight", w)  # a bool or a string is no weight
        return Sum(terms=tuple((w * k, m) for k, m in _terms(self)))

    __rmul__ = __mul__

    @classmethod
    def info(cls) -> str:
        """Docstring summary and declared parameters, for listing models."""
        head = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else cls.__name__
        lines = [f"{cls.__name__}: {head}"]
        width = max([12] + [len(p.name) for p in cls.parameters()])  # the names' column, aligned
        for p in cls.parameters():
            old = f"; old name{'s' if len(p.aliases) > 1 else ''} {', '.join(p.aliases)}" if p.aliases else ""
            default = f"{'(required)':<22}" if p.required else f"default={p.default!r:<14}"
            lines.append(f"    {p.name:<{width}} {default} {p.doc} ({p.range_text()}{old})")
        return "\n".join(lines)


#: a weight of an incoherent sum: a factor (constraints.FACTOR_MAX), not a bool or a string
WEIGHT = Interval(0.0, FACTOR_MAX)


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

    terms: tuple = param(
        (), "tuple of (weight, model) pairs", Instance(tuple, list, text="a tuple of (weight, model) pairs")
    )

    depolarizing = True
    correspondence = Correspondence("incoherent sum ``m1 + m2``, ``w * m`` (seed 003 Sec. 2.6 combination)")

    def _validate(self):
        if not self.terms:
            raise ValueError("terms must hold at least one (weight, model) pair")
        clean = []
        for item in self.terms:
            if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[1], Model)):
                raise ValueError("terms must be (weight, model) pairs with a Model instance")
            clean.append((WEIGHT.check("weight", item[0]), item[1]))
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

    _numpy_sets = True  # its terms evaluate their own parameters

    def _mueller16(self, ti, tr, pr):
        # a weight of 1 multiplies nothing (1 * x is x, bit for bit), and the sum is added in
        # place once it is an array of its own: a term's result may be shared or read-only,
        # and the sum's is the caller's
        total, owned = None, False
        for w, m in self.terms:
            block, fresh = m.flat_mueller16(ti, tr, pr), w != 1.0
            if fresh:
                block = w * block
            if total is None:
                total, owned = block, fresh
            elif owned:
                total += block
            else:
                total, owned = total + block, True
        return total if owned else total.copy()

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
