"""The conformance checks: what any BRDF model must do (registered with
:func:`.conformance.model_check`; each takes the model and a context).

Evaluation rules (DESIGN.md "Conventions"): shapes and broadcasting, dtypes, ``out=``,
determinism, picklability.  Physics: finiteness, ``M00 >= 0``, realizability,
reciprocity and energy on a grid of extreme geometries, and the stability sweep's
parameter extremes for a model with declared parameters.  The SCATMECH comparison is in
:mod:`.conformance_scatmech`.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import math
import pickle

import numpy as np

from scatterbench import models
from scatterbench.models.params import Declared
from scatterbench.models.polarization import coherency_eigenvalues
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.probes import extreme_geometries, random_geometries
from scatterbench.validation.numerics.reciprocity import reciprocity_errors
from scatterbench.validation.studies.edge_sweep import (
    classify,
    edge_geometries,
    edge_instances,
    energy_fields,
    load_accepted,
    model_hit_fraction,
    sweep_model,
)
from scatterbench.validation.studies.findings import Finding

from .conformance import (
    accepted_reason,
    as_model,
    claims,
    evaluate,
    finding_of,
    jones_of,
    model_check,
    mueller_of,
    skipped,
    verdict,
    where,
)

__all__ = [
    "kit_geometries",
    "energy_incidences",
    "BROADCAST_TOL",
    "DTYPE_TOL",
    "RECIPROCITY_TOL",
    "REALIZABLE_TOL",
    "ENERGY_TOL",
    "ENERGY_BUDGET",
    "ENERGY_LADDER_DEG",
    "QUICK_LADDER_DEG",
    "mirror_verified",
]

#: relative to M00: the same geometry evaluated in another batch, shape or dtype (vectorized
#: and scalar transcendental functions may differ in the last bit; DESIGN.md holds compiled
#: kernels to 1e-12 of M00, and a float32 computation would be off by ~1e-7)
BROADCAST_TOL = 1e-12
DTYPE_TOL = 1e-9
#: relative to M00, as the stability sweep
RECIPROCITY_TOL = 1e-9
REALIZABLE_TOL = -1e-9
#: the energy integral's absolute tolerance and evaluation budget per incidence (as the sweep)
ENERGY_TOL = 1e-3
ENERGY_BUDGET = 2_000_000
#: the energy ladder (degrees): normal, oblique, and grazing incidence, where models without
#: shadowing gather more light than the beam brings (accepted findings)
ENERGY_LADDER_DEG = (0.0, 45.0, 75.0, 89.99)
QUICK_LADDER_DEG = (0.0, 89.99)


def kit_geometries(model):
    """The kit's grid ``(ti, tr, pr)``: the extreme geometries of :mod:`.common` (0, 1e-9,
    30, 60, 89.99, 90 deg; exact specular and retroreflection; phi 0, +-pi, pi/2, 1e-12),
    the stability sweep's edge geometries of ``model`` (critical angles of its declared
    indices +- 1e-9), and 200 seeded random interior ones."""

    parts = [extreme_geometries(), edge_geometries(model), random_geometries(200, seed=14, max_deg=89.0)]
    return tuple(np.concatenate(p) for p in zip(*parts, strict=True))


def energy_incidences(ctx):
    """The incidences (radians) of the energy ladder of a run."""
    return tuple(math.radians(d) for d in (QUICK_LADDER_DEG if ctx.quick else ENERGY_LADDER_DEG))


def _relative(M, R):
    """Per geometry ``max |M - R| / |R00|`` of ``(n, 4, 4)`` stacks (0 where both vanish)."""
    d = np.max(np.abs(M - R), axis=(-1, -2))
    scale = np.abs(R[..., 0, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(d == 0, 0.0, d / np.where(scale > 0, scale, 0.0))


def _worst(e):
    """``(value, k)``: the largest entry of ``e`` and its index (non-finite entries first)."""
    e = np.where(np.isfinite(e), e, np.inf)
    k = int(np.argmax(e))
    return float(e[k]), k


def _claims_stochastic(model):
    return bool(claims(model, "stochastic", hasattr(model, "seed")))


def _reseeded(model, seed):
    """A copy of ``model`` with another ``seed`` (``replace`` for declared models and
    dataclasses, else a deep copy with the attribute set); ``None`` when none can be made."""
    try:
        if isinstance(model, Declared):
            return model.replace(seed=seed)
        if dataclasses.is_dataclass(model):
            return dataclasses.replace(model, seed=seed)
        other = copy.deepcopy(model)
        other.seed = seed
        return other
    except Exception:  # noqa: BLE001 - a model that refuses a new seed cannot show its noise
        return None


def _seed_spread(model, ctx):
    """``(difference, seeds, where)``: the largest relative difference between the model's numbers
    and a copy's with another seed on a few geometries (0: the same numbers, the claim false;
    NaN: no copy with another seed could be made), memoized."""

    def compute():
        seed = claims(model, "seed", None)
        other_seed = (seed + 1) if isinstance(seed, int) and not isinstance(seed, bool) else 12345
        other = _reseeded(model, other_seed)
        ti, tr, pr = random_geometries(8, seed=11)
        if other is None:
            return math.nan, (seed, other_seed), ""
        e, k = _same(model, [other], ti, tr, pr)
        return e, (seed, other_seed), where(ti, tr, pr, k)

    return _memo(ctx, "seed spread", model, compute)


def _stochastic(model, ctx):
    """True when the model claims to be stochastic and the claim holds (two seeds give
    different numbers): only then are the exact checks (energy, reciprocity, mirror symmetry)
    skipped.  A claim is not trusted: a deterministic model that claims it would skip them."""
    return _claims_stochastic(model) and _seed_spread(model, ctx)[0] > 0.0


def _memo(ctx, key, model, fn):
    """``fn()`` once per context and model (kept alive with it, so ``id`` stays unique)."""
    k = (key, id(model))
    if k not in ctx.memo:
        ctx.memo[k] = (model, fn())
    return ctx.memo[k][1]


# --------------------------------------------------------------------------- evaluation rules
_TI = np.array([0.1, 0.6, 1.2])
_TR = np.array([0.05, 0.7, 1.3, 0.2])
_PR = np.array([0.4, -2.5])


def _repeatable(model, ctx):
    """Whether two calls at the same geometries give the same numbers (once per context):
    the checks that compare numbers between calls need it (determinism judges it)."""

    def compute():
        ti, tr, pr = random_geometries(16, seed=12)
        a, b = (np.asarray(mueller_of(model, ti, tr, pr)) for _ in range(2))
        return bool(np.array_equal(a, b, equal_nan=True))

    return _memo(ctx, "repeatable", model, compute)


def _shapes(args):
    return " x ".join(str(np.shape(a)) for a in args)


def _judge_forms(check, model, ctx, forms, tol, what):
    """Each call form ``(label, args, reference, geometry)`` must give the reference's shape
    and (for a model that repeats its numbers) its values within ``tol`` of M00."""
    repeat = _repeatable(model, ctx)
    worst, at, label = 0.0, "", ""
    for name, args, ref, geometry in forms:
        try:
            M = np.asarray(mueller_of(model, *args))
        except Exception as exc:  # noqa: BLE001 - a call form the model cannot take fails this check
            return verdict(check, math.inf, tol, f"{name} {_shapes(args)} raised {type(exc).__name__}: {exc}")
        if M.shape != ref.shape:
            return verdict(
                check, math.inf, tol, f"{name} {_shapes(args)} gave shape {M.shape}, not {ref.shape}"
            )
        if repeat:
            e, k = _worst(_relative(M.reshape(-1, 4, 4).astype(float), ref.reshape(-1, 4, 4)))
            if e > worst:
                worst, label = e, f"{name} (result dtype {M.dtype})"
                at = where(*(np.broadcast_to(np.asarray(g, float), ref.shape[:-2]) for g in geometry), k)
    if not repeat:
        why = "shapes right; values not compared: the model does not repeat its own numbers (see determinism)"
        return skipped(check, why)
    return verdict(check, worst, tol, what + (f"; worst: {label}" if label else ""), where=at)


def _reference(model):
    """The Mueller matrix at each of the 3 x 4 x 2 geometries, one scalar call each, or the
    failure of the first scalar call that does not give a (4, 4) result."""
    R = np.empty((3, 4, 2, 4, 4))
    for i, j, k in np.ndindex(3, 4, 2):
        M = np.asarray(mueller_of(model, _TI[i], _TR[j], _PR[k]))
        if M.shape != (4, 4):
            at = where(_TI[i], _TR[j], _PR[k])
            return verdict(
                "broadcasting",
                math.inf,
                BROADCAST_TOL,
                f"scalar angles gave shape {M.shape}, not (4, 4)",
                where=at,
            )
        R[i, j, k] = M
    return R


def _forms(R):
    """``(label, args, reference, geometry)`` of every call form, the reference from scalar calls."""
    ti, tr, pr = np.meshgrid(_TI, _TR, _PR, indexing="ij")
    n = models.CHUNK + 5  # longer than one of models.Model's evaluation chunks
    rep = -(-n // ti.size)
    flat = (ti.ravel(), tr.ravel(), pr.ravel())
    long_args = tuple(np.tile(a, rep)[:n] for a in flat)
    zero_d = (np.asarray(_TI[1]), np.asarray(_TR[2]), np.asarray(_PR[1]))
    outer = (_TI[:, None, None], _TR[None, :, None], _PR[None, None, :])
    mixed = (_TI[2], _TR, _PR[0])
    return [
        ("0-d arrays", zero_d, R[1, 2, 1], zero_d),
        ("equal-shape arrays", flat, R.reshape(-1, 4, 4), flat),
        ("outer broadcast", outer, R, outer),
        ("scalar and array", mixed, R[2, :, 0], mixed),
        (f"{n} geometries (chunked)", long_args, np.tile(R.reshape(-1, 4, 4), (rep, 1, 1))[:n], long_args),
    ]


@model_check(
    tests="DESIGN.md: inputs broadcast against each other, the result has shape broadcast_shape + (4, 4); "
    "scalar, 0-d, array, broadcast and chunked (more than models.CHUNK) calls give the same numbers"
)
def check_broadcasting(model, ctx):
    R = _reference(model)
    if not isinstance(R, np.ndarray):
        return R
    what = "max |M - M(scalar calls)| / M00 over 5 call forms"
    return _judge_forms("broadcasting", model, ctx, _forms(R), BROADCAST_TOL, what)


@model_check(
    tests="DESIGN.md: float64 evaluation whatever the angles' dtype (float32 arrays, Python and numpy integers)"
)
def check_dtypes(model, ctx):
    f32 = tuple(a.astype(np.float32) for a in random_geometries(32, seed=7, max_deg=80.0))
    ints = (np.array([0, 1]), np.array([1, 0]), np.array([-3, 3]))
    forms = []
    for name, args in (("float32 arrays", f32), ("Python ints", (0, 1, 2)), ("int64 arrays", ints)):
        as64 = tuple(np.asarray(a, dtype=float) for a in args)
        forms.append((name, args, np.asarray(mueller_of(model, *as64)), as64))
    return _judge_forms("dtypes", model, ctx, forms, DTYPE_TOL, "max |M(x) - M(float64(x))| / M00")


def _takes_out(model):
    try:
        params = inspect.signature(model.mueller).parameters
    except (TypeError, ValueError):
        return False
    return "out" in params


@model_check(
    tests="scatterbench.models.Model.mueller(..., out=): the (16, N) float64 element-major result is written into out"
)
def check_out_argument(model, ctx):
    if not _takes_out(model):
        return skipped("out argument", "mueller() takes no out= argument")
    ti, tr, pr = random_geometries(37, seed=8)
    try:
        mueller_of(model, ti, tr, pr, out=np.empty((16, ti.size + 1)))
    except ValueError:
        pass
    else:
        why = "an out of shape (16, N + 1) was accepted (ValueError expected)"
        return verdict("out argument", math.inf, BROADCAST_TOL, why)
    buf = np.full((16, ti.size), np.nan)
    M = np.asarray(mueller_of(model, ti, tr, pr, out=buf))
    if not _repeatable(model, ctx):
        why = "values not compared: the model does not repeat its own numbers (see determinism)"
        return skipped("out argument", why)
    ref = np.asarray(mueller_of(model, ti, tr, pr))
    written = np.moveaxis(buf.reshape(4, 4, -1), -1, 0)
    e, k = _worst(np.maximum(_relative(M, ref), _relative(written, ref)))
    detail = "max |M(out=) - M| / M00 over the result and the buffer"
    return verdict("out argument", e, BROADCAST_TOL, detail, where=where(ti, tr, pr, k))


# --------------------------------------------------------------------------- physics on the grid
def _grid(model, ctx):
    """``(ti, tr, pr, M, J, warned)`` on :func:`kit_geometries`, once per context; ``J`` the
    Jones matrices of a non-depolarizing model (one with ``jones``), else ``None``."""

    def compute():
        ti, tr, pr = kit_geometries(model)
        M, warned = evaluate(model, ti, tr, pr)
        if M.shape != (ti.size, 4, 4):
            raise ValueError(f"mueller gave shape {M.shape} for {ti.size} geometries, not ({ti.size}, 4, 4)")
        J = None
        if callable(getattr(model, "jones", None)) and not claims(model, "depolarizing", False):
            J = np.asarray(jones_of(model, ti, tr, pr))
        return ti, tr, pr, M.reshape(-1, 4, 4), J, warned

    return _memo(ctx, "grid", model, compute)


@model_check(
    tests="DESIGN.md: no NaN or inf from an in-range geometry (grazing, normal, exact specular and "
    "retroreflection, phi = +-pi, critical angles), in the Mueller and the Jones matrices"
)
def check_finite(model, ctx):
    ti, tr, pr, M, J, warned = _grid(model, ctx)
    bad = ~np.all(np.isfinite(M), axis=(-1, -2))
    if J is not None:
        bad |= ~np.all(np.isfinite(J.reshape(-1, 2, 2)), axis=(-1, -2))
    at = where(ti, tr, pr, int(np.argmax(bad))) if bad.any() else ""
    detail = f"geometries with a non-finite element, of {bad.size}; {warned} floating-point warnings"
    return verdict("finite", int(bad.sum()), 0, detail, where=at)


@model_check(tests="a BRDF is non-negative: M00 >= 0 on the grid")
def check_nonnegative(model, ctx):
    ti, tr, pr, M, _, _ = _grid(model, ctx)
    m00 = np.where(np.isfinite(M[:, 0, 0]), M[:, 0, 0], np.inf)  # non-finite values: check finite
    k = int(np.argmin(m00))
    return verdict(
        "M00 >= 0", float(m00[k]), 0.0, "min M00 (1/sr) on the grid", where=where(ti, tr, pr, k), op=">="
    )


@model_check(
    tests="realizability (Cloude): the coherency matrix of M is positive semi-definite, "
    "eigenvalues >= -1e-9 M00 (models.polarization.coherency_eigenvalues)"
)
def check_realizable(model, ctx):
    ti, tr, pr, M, _, _ = _grid(model, ctx)
    live = np.all(np.isfinite(M), axis=(-1, -2)) & (M[:, 0, 0] > 1e-250)
    if not live.any():
        return skipped("realizable", "no geometry of the grid scatters light (M00 > 1e-250)")
    ev = coherency_eigenvalues(M[live])[:, 0] / M[live, 0, 0]
    k = int(np.argmin(ev))
    detail = f"min coherency eigenvalue / M00 over {int(live.sum())} lit geometries"
    return verdict(
        "realizable",
        float(ev[k]),
        REALIZABLE_TOL,
        detail,
        where=where(*(a[live] for a in (ti, tr, pr)), k),
        op=">=",
    )


def _mirror_errors(model, ctx):
    """``(errors, ti, tr, pr)``: per grid geometry ``|M00(phi) - M00(-phi)| / max`` of the two
    (0 where both vanish), once per context."""

    def compute():
        ti, tr, pr, M, _, _ = _grid(model, ctx)
        R, _ = evaluate(model, ti, tr, -pr)
        a, b = M[:, 0, 0], np.asarray(R).reshape(-1, 4, 4)[:, 0, 0]
        scale = np.maximum(np.abs(a), np.abs(b))
        with np.errstate(divide="ignore", invalid="ignore"):
            e = np.where(a == b, 0.0, np.abs(a - b) / np.where(scale > 0, scale, 1.0))
        return e, ti, tr, pr

    return _memo(ctx, "mirror", model, compute)


def mirror_verified(model, ctx) -> bool:
    """True when the model claims ``mirror_symmetric`` and the claim holds on the grid (to
    :data:`RECIPROCITY_TOL`): only then may an integral halve its azimuth range.  A claim is
    not trusted: a model that claims it and is brighter at negative azimuths would otherwise
    have half its light (and any energy it creates) integrated away."""
    if not claims(model, "mirror_symmetric", False) or _stochastic(model, ctx):
        return False
    e = _mirror_errors(model, ctx)[0]
    return bool(np.all(np.isfinite(e)) and e.max() <= RECIPROCITY_TOL)


@model_check(
    tests="a claim of mirror symmetry (mirror_symmetric = True: M00 even in phi_r, which lets the "
    "integrator halve its domain) holds on the grid: |M00(phi) - M00(-phi)| / M00 <= 1e-9"
)
def check_mirror_symmetry(model, ctx):
    if not claims(model, "mirror_symmetric", False):
        return skipped("mirror symmetry", "the model does not claim mirror symmetry (mirror_symmetric)")
    if _stochastic(model, ctx):
        return skipped("mirror symmetry", "stochastic: its noise differs between phi and -phi")
    e, ti, tr, pr = _mirror_errors(model, ctx)
    v, k = _worst(e)
    detail = "max |M00(phi) - M00(-phi)| / M00 on the grid (the model claims mirror_symmetric)"
    return verdict("mirror symmetry", v, RECIPROCITY_TOL, detail, where=where(ti, tr, pr, k))


def _reciprocity_errors(model, ctx):
    """``(geometry, errors, note)``: :func:`scatterbench.validation.numerics.reciprocity.reciprocity_errors`
    on the grid, kept where both paths are finite (non-finite values are the finite check's
    failure), with the geometries they belong to."""

    ti, tr, pr, M, J, _ = _grid(model, ctx)
    e = reciprocity_errors(as_model(model), ti, tr, pr, mueller=M, jones=J)
    fin = e.finite
    note = f"{int(np.sum(e.live & fin))} lit geometries"
    if not fin.all():
        note += f" ({int(np.sum(~fin))} non-finite ones left to the finite check)"
    kept = {
        "scalar": e.scalar[fin],
        "mueller": e.mueller[fin],
        "jones": None if J is None or e.jones is None else e.jones[fin],
    }
    return (ti[fin], tr[fin], pr[fin]), kept, note


@model_check(
    tests="Helmholtz reciprocity: f(i -> r) = f(r -> i) and, for polarization, M_rev = D M^T D with "
    "D = diag(1, 1, -1, 1) in the psps basis, and J_rev = Z J^T Z with Z = diag(1, -1) for a "
    "non-depolarizing model with jones (validation.numerics.reciprocity)"
)
def check_reciprocity(model, ctx):
    claim = claims(model, "reciprocal", True)
    if claim is False:
        return skipped("reciprocity", "the model does not claim reciprocity (reciprocal = False)")
    if _stochastic(model, ctx):
        return skipped("reciprocity", "stochastic: reciprocal only within its sampling error, not exactly")
    geometry, errors, note = _reciprocity_errors(model, ctx)
    e, k = _worst(errors["scalar"])
    out = [
        verdict(
            "reciprocity: M00",
            e,
            RECIPROCITY_TOL,
            f"max |f - f_rev| / f over {note}",
            where=where(*geometry, k),
        )
    ]
    polarized = [("Mueller", "mueller", "max |M_rev - D M^T D| / M00")]
    if errors["jones"] is not None:
        polarized.append(("Jones", "jones", "max |J_rev - phase Z J^T Z| / sqrt(M00)"))
    for name, key, what in polarized:
        if claim == "scalar":
            why = "the model claims scalar reciprocity only (reciprocal = 'scalar')"
            out.append(skipped(f"reciprocity: {name}", why))
        else:
            e, k = _worst(errors[key])
            detail = f"{what} over {note}"
            out.append(verdict(f"reciprocity: {name}", e, RECIPROCITY_TOL, detail, where=where(*geometry, k)))
    return out


# --------------------------------------------------------------------------- energy
def _energy_bound(model):
    bound = claims(model, "energy_bound", 1.0)
    if (
        isinstance(bound, bool)
        or not isinstance(bound, int | float)
        or not (math.isfinite(bound) and bound > 0)
    ):
        raise ValueError(f"energy_bound must be a finite number > 0; got {bound!r}")
    return float(bound)


def _energy_reason(model, ti, r, bound):
    """The accepted finding (``(reason, condition)`` or ``None``) that explains the
    integrated reflectance ``r`` above ``bound`` at ``ti``, from the fields the stability
    sweep gives its energy findings (:func:`scatterbench.validation.studies.edge_sweep.energy_fields`);
    the hit fraction (an integral) only when needed."""

    accepted = load_accepted()
    fields = energy_fields(model, ti, r.value, r.error, bound, hit=False)
    found = accepted_reason(model, "energy", fields, accepted)
    if found is None and (h := model_hit_fraction(model, ti)) is not None:
        found = accepted_reason(model, "energy", {**fields, "hit_fraction": h}, accepted)
    return found


def _energy_ladder(model, ctx):
    view = as_model(model)
    half = mirror_verified(model, ctx)  # a claim of mirror symmetry only where it holds
    out = []
    for ti in energy_incidences(ctx):
        r = integrated_reflectance(view, ti, tol=ENERGY_TOL, max_evaluations=ENERGY_BUDGET, symmetric=half)
        out.append((ti, r))
    return out


def _declared_excess(bound):
    """The finding of a reflectance above 1 within a declared ``energy_bound`` above 1: the
    model says it is not energy-conserving, so it does not pass (it creates light), and fails
    only above what it declared."""
    return Finding(
        fails=False,
        fails_if=f"the integrated reflectance exceeds the declared energy_bound {bound:g}",
    )


@model_check(
    tests="energy conservation: the integrated reflectance (validation.integrated_reflectance, "
    "M00 cos(theta_r) dOmega) at a ladder of incidences stays below 1 or the declared energy_bound"
)
def check_energy(model, ctx):
    if _stochastic(model, ctx):
        return skipped(
            "energy", "stochastic: a noisy integrand leaves the cubature's error estimate meaningless"
        )
    bound = _energy_bound(model)
    ladder = _memo(ctx, "energy", model, lambda: _energy_ladder(model, ctx))
    shown = ", ".join(f"{math.degrees(ti):g} deg {r.value:.4g} +- {r.error:.1g}" for ti, r in ladder)
    src = "declared energy_bound" if hasattr(model, "energy_bound") else "energy conservation"
    what = "transmittance (a BTDF)" if claims(model, "transmission", False) else "reflectance"
    detail = (
        f"max over incidences of R - its error, R the integrated {what}: {shown}; bound {bound:g} ({src})"
    )
    unresolved = [ti for ti, r in ladder if not r.converged]
    if unresolved:
        at = ", ".join(f"{math.degrees(t):g}" for t in unresolved)
        why = f"the integral did not reach {ENERGY_TOL:g} within {ENERGY_BUDGET} evaluations at {at} deg; {detail}"
        return verdict("energy", math.nan, bound, why)
    lower = [r.value - r.error for _, r in ladder]
    k = int(np.argmax(lower))
    at = f"theta_i={math.degrees(ladder[k][0]):.6g} deg"
    if bound > 1.0 and 1.0 < lower[k] <= bound:
        # a declared bound above 1 is not trusted as a pass: above 1 the model creates light
        detail += "; above 1 (energy conservation) within the declared bound: a finding, not a pass"
        return verdict("energy", lower[k], 1.0, detail, where=at, finding=_declared_excess(bound))
    reasons = {ti: _energy_reason(model, ti, r, bound) for ti, r in ladder if r.value - r.error > bound}
    if reasons and all(reasons.values()):
        reason, condition = reasons[ladder[k][0]]  # the worst incidence's
        detail += f"; accepted finding: {' '.join(reason.split())}"
        return verdict("energy", lower[k], bound, detail, where=at, finding=finding_of(reason, condition))
    return verdict("energy", lower[k], bound, detail, where=at)


# --------------------------------------------------------------------------- determinism, pickle
def _same(model, others, ti, tr, pr):
    """``(worst, k)``: the largest relative difference of ``others``' numbers from the model's."""
    ref = np.asarray(mueller_of(model, ti, tr, pr))
    e = np.zeros(ti.size)
    for m in others:
        e = np.maximum(e, _relative(np.asarray(mueller_of(m, ti, tr, pr)), ref))
    return _worst(e)


@model_check(
    tests="a claim to be stochastic (stochastic = True, or a seed attribute) holds: a copy with "
    "another seed gives different numbers (a false claim would skip energy, reciprocity and mirror symmetry)"
)
def check_stochastic_claim(model, ctx):
    if not _claims_stochastic(model):
        return skipped(
            "stochastic claim", "the model does not claim to be stochastic (no seed, stochastic unset)"
        )
    e, (seed, other), at = _seed_spread(model, ctx)
    detail = f"max |dM| / M00 between seed {seed!r} and a copy with seed {other!r}"
    if math.isnan(e):
        detail += ": no copy with another seed could be made (replace(seed=...) or setting .seed)"
    elif e == 0.0:
        detail += ": the same numbers, so the model is deterministic and the exact checks run"
    return verdict("stochastic claim", e, 0.0, detail, where=at, op=">")


@model_check(
    tests="DESIGN.md: the same seed gives the same numbers (a stochastic model: fresh copies with the "
    "same seed and repeated calls; every model: repeated calls)"
)
def check_determinism(model, ctx):
    ti, tr, pr = random_geometries(48, seed=9)
    others = [model]
    how = "a repeated call"
    if _stochastic(model, ctx):
        others += [copy.deepcopy(model), copy.deepcopy(model)]
        how = f"a repeated call and two copies with seed {claims(model, 'seed', None)!r}"
    else:
        how += " (not stochastic: no seed to copy)"
    e, k = _same(model, others, ti, tr, pr)
    return verdict(
        "determinism", e, 0.0, f"max |dM| / M00 between the first call and {how}", where=where(ti, tr, pr, k)
    )


@model_check(
    tests="picklable (the distributed executors send models to worker processes): the copy gives the same numbers"
)
def check_pickle(model, ctx):
    try:
        clone = pickle.loads(pickle.dumps(model))
    except Exception as exc:  # noqa: BLE001 - any pickling error is this check's failure
        return verdict("pickle", math.inf, 0.0, f"pickle round trip raised {type(exc).__name__}: {exc}")
    ti, tr, pr = random_geometries(16, seed=10)
    if not _repeatable(model, ctx):
        return skipped(
            "pickle", "pickled and restored, but the model does not repeat its own numbers (see determinism)"
        )
    e, k = _same(model, [clone], ti, tr, pr)
    return verdict("pickle", e, 0.0, "max |dM| / M00 of the unpickled copy", where=where(ti, tr, pr, k))


# --------------------------------------------------------------------------- parameter extremes
@model_check(
    tests="the stability sweep (validation/studies/edge_sweep.py) on the model: each declared parameter at "
    "its edges, at edge geometries: no fp warning, non-finite, negative or unrealizable value, no "
    "reciprocity violation (findings accepted in accepted_findings.toml are findings)",
    slow=True,
)
def check_parameter_extremes(model, ctx):

    if not isinstance(model, Declared) or not type(model).parameters():
        return skipped(
            "parameter extremes",
            "the model declares no parameters (models.Model with models.params.param fields)",
        )
    found = []
    instances = edge_instances(model)
    for inst in instances:
        found += sweep_model(inst, energy=False)
    own = type(model).__module__.startswith("scatterbench.models.")
    ok, bad = classify(found, load_accepted() if own else [])
    top = (bad or ok)[0][0] if found else None
    at = f"{top.params} at {top.where}" if top else ""
    detail = f"findings over {len(instances)} edge instances ({len(ok)} accepted)"
    if top:
        detail += f"; first: {top.kind} {top.value:.4g}"
    finding = Finding(fails=bool(bad), fails_if="a finding is not accepted in accepted_findings.toml")
    return verdict(
        "parameter extremes", len(found), 0, detail, where=at, finding=finding if ok and not bad else None
    )
