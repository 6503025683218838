"""The conformance registry: the check registry (:mod:`.registry`) seen from outside.

The harness's checks (:func:`.registry.check`) each test one property of scatterbench's
own models; the checks registered here with :func:`model_check` each test one property
*any* model must have, and take the model as an argument: ``f(model, ctx) -> Check``.
They share :func:`.registry.judge` (the one place a measured value and its limit become a
status) and :class:`.registry.Check` (as :class:`ModelCheck`, which adds the model and
the worst geometry), and :class:`.registry.CheckContext` (the quick flag, the seed and the
memo a report section shares).  :mod:`scatterbench.validation.testing` is the public entry
(``check_model``, ``parametrize_with_checks``); the checks are in
:mod:`.conformance_checks` and :mod:`.conformance_scatmech`.

What counts as a model (duck-typed): any object with ``mueller(theta_i, theta_r, phi_r)``
that broadcasts numpy arrays (radians) and returns ``(..., 4, 4)`` Mueller matrices in the
psps basis of DESIGN.md.  :func:`as_model` views such an object as a
:class:`scatterbench.models.Model` for the integrator, the reciprocity relations and the stability
sweep, reading the optional attributes :data:`ATTRIBUTES` documents.

A result's status is ``pass``, ``fail``, ``finding`` (outside its limit where a finding of
a paper, accepted with its reason in ``validation/studies/accepted_findings.toml``,
explains it) or ``skip`` (the check needs a capability the model does not have; the
detail says which).
"""

from __future__ import annotations

import dataclasses
import math
import traceback
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from scatterbench.models.contributed import Conformant, as_model
from scatterbench.validation.numerics.probes import fp_warnings
from scatterbench.validation.studies import edge_sweep
from scatterbench.validation.studies.findings import Finding

from .registry import Check, CheckContext, judge

__all__ = [
    "ATTRIBUTES",
    "ModelCheck",
    "ConformanceSpec",
    "model_check",
    "conformance_checks",
    "verdict",
    "skipped",
    "run_model_checks",
    "Conformant",
    "as_model",
    "evaluate",
    "readonly",
    "mueller_of",
    "jones_of",
    "where",
    "claims",
    "accepted_reason",
    "finding_of",
]

#: The optional attributes a model may set, and what the kit does with each.
ATTRIBUTES = {
    "reciprocal": "True (default): Helmholtz reciprocity in M00 and in the Mueller relation "
    "M_rev = D M^T D, D = diag(1, 1, -1, 1) (and J_rev = Z J^T Z for a model with jones); "
    "'scalar': in M00 only; False: not claimed (skipped)",
    "energy_bound": "upper bound of the integrated reflectance (default 1; e.g. 4 pi for a "
    "published normalization that is not energy-normalized)",
    "stochastic": "True for a Monte Carlo model (default: True when it has a 'seed' attribute); "
    "the same seed must give the same numbers; reciprocity and energy are then not judged "
    "by exact comparisons (they hold within the sampling error only)",
    "seed": "the random seed of a stochastic model",
    "scatmech": "(name, parameters): the equivalent SCATMECH model and its parameters as "
    'SCATMECH strings, e.g. ("Facet_BRDF_Model", {"substrate": "(1.37,7.62)", '
    '"sdf": "Exponential_Slope_Distribution_Function", "sdf.s": 0.1})',
    "transmission": "True for a BTDF (the second polar angle is measured from -z)",
    "jones": "jones(theta_i, theta_r, phi_r) -> (..., 2, 2) for a non-depolarizing model: "
    "its reciprocity relation J_rev = Z J^T Z is checked too",
    "rotated": "rotated(angle) -> the model of the sample rotated about z, for anisotropic "
    "samples (without it the model is taken to be azimuthally isotropic)",
    "lobe": "lobe(theta_i) -> (theta, phi, width) of a narrow lobe, a hint for the integrator",
    "mirror_symmetric": "True when M00 is even in phi_r: verified on the grid (check mirror symmetry); "
    "the energy integral halves its domain only where the claim holds there",
}


@dataclass(frozen=True)
class ModelCheck(Check):
    """One conformance result: a :class:`~.registry.Check` for one model, with the worst
    geometry (``where``) and ``status`` ``"skip"`` when the check does not apply."""

    model: str = ""
    where: str = ""

    @property
    def message(self) -> str:
        """The check, the model, the status, the measured value against its limit, the worst
        geometry and the detail, on one line."""
        head = f"{self.model}: {self.name} {self.status.upper()}"
        if self.status == "skip":
            return f"{head}: {self.detail}"
        at = f" at {self.where}" if self.where else ""
        return (
            f"{head}: measured {self.measured:.4g} (limit {self.op} {self.tolerance:.4g}){at}; {self.detail}"
        )


@dataclass(frozen=True)
class ConformanceSpec:
    """A registered conformance check: ``name`` (stable, used in pytest ids), the function
    ``f(model, ctx) -> ModelCheck | list[ModelCheck]``, what it tests, and whether it is
    slow (quick runs skip it)."""

    name: str
    func: Callable
    tests: str
    slow: bool = False


_MODEL_CHECKS: dict[str, ConformanceSpec] = {}


def model_check(*, tests, slow=False):
    """Register ``check_NAME(model, ctx)`` as the conformance check ``NAME``.

    Parameters
    ----------
    tests : str
        The property it tests and where it is stated (DESIGN.md, a paper).
    slow : bool
        Skipped (with a note) by quick runs.
    """
    if not tests:
        raise ValueError("tests must say which property the check tests")

    def register(fn):
        name = fn.__name__.removeprefix("check_")
        _MODEL_CHECKS[name] = ConformanceSpec(name, fn, tests, bool(slow))
        return fn

    return register


def conformance_checks(names=None):
    """The registered conformance checks in run order, or those named (``ValueError``
    naming an unknown one).  (The package's ``__init__`` imports the modules that register
    them, :mod:`.conformance_checks` and :mod:`.conformance_scatmech`, before this one can be
    called.)"""
    if names is None:
        return list(_MODEL_CHECKS.values())
    unknown = [n for n in names if n not in _MODEL_CHECKS]
    if unknown:
        raise ValueError(f"checks: unknown name(s) {', '.join(unknown)}; known: {', '.join(_MODEL_CHECKS)}")
    return [_MODEL_CHECKS[n] for n in names]


def verdict(name, measured, tolerance, detail="", *, where="", op="<=", finding=None) -> ModelCheck:
    """:func:`.registry.judge` of ``measured op tolerance``, with the worst geometry."""
    c = judge(name, measured, tolerance, detail, op=op, finding=finding)
    return ModelCheck(**c.as_dict(), where=where)


def skipped(name, why) -> ModelCheck:
    """A check that does not apply to the model: status ``skip``, ``why`` in the detail."""
    return ModelCheck(name, math.nan, math.nan, "skip", why)


def _stamped(spec, label, r):
    return dataclasses.replace(r, id=spec.name, paper=spec.tests, slow=spec.slow, model=label)


def run_model_checks(model, ctx=None, specs=None, label=None) -> list[ModelCheck]:
    """Every result of the conformance checks ``specs`` on ``model``.

    A check that raises fails, with the exception in its detail: a model that raises on
    valid input fails the check that called it.  Slow checks are skipped when
    ``ctx.quick``.  Results are kept in ``ctx.memo`` (a check runs once per model and
    context).

    Parameters
    ----------
    model : object
        Anything with ``mueller(theta_i, theta_r, phi_r)``.
    ctx : CheckContext, optional
        Quick flag and memo (default: a fresh full-run context).
    specs : list of ConformanceSpec, optional
        Default: every registered conformance check.
    label : str, optional
        The model's name in the results (default: its class name).

    Returns
    -------
    list of ModelCheck
    """
    ctx = ctx if ctx is not None else CheckContext()
    specs = conformance_checks() if specs is None else specs
    label = label or type(model).__name__
    out = []
    for spec in specs:
        key = ("conformance", id(model), spec.name)
        if key not in ctx.memo:
            ctx.memo[key] = (model, [_stamped(spec, label, r) for r in _run_one(spec, model, ctx)])
        out.extend(ctx.memo[key][1])
    return out


def _run_one(spec, model, ctx):
    if spec.slow and ctx.quick:
        return [skipped(spec.name, "slow check: skipped by quick runs")]
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = spec.func(model, ctx)
    except Exception as exc:  # noqa: BLE001 - a model that raises fails the check that called it
        tb = traceback.format_exc(limit=-1).strip().splitlines()
        where_ = tb[-3].strip() if len(tb) >= 3 else ""
        what = f"raised {type(exc).__name__}: {exc} [{where_}]"
        if isinstance(exc, ValueError) and "read-only" in str(exc):
            what = "the model writes into its input arrays (the kit hands it read-only copies); " + what
        return [verdict(spec.name, math.nan, 0.0, what)]
    out = out if isinstance(out, list) else [out]
    if not out or not all(isinstance(r, ModelCheck) for r in out):
        return [verdict(spec.name, math.nan, 0.0, "the check returned no ModelCheck")]
    return out


# --------------------------------------------------------------------------- the model view
def claims(model, attribute, default):
    """The model's optional ``attribute`` (:data:`ATTRIBUTES`), ``default`` when unset."""
    return getattr(model, attribute, default)


def readonly(*arrays):
    """Fresh read-only copies of the geometry inputs handed to a model: a model that writes
    into its inputs cannot corrupt the kit's grids for the checks after it (it fails the check
    that called it instead, naming what it did: :func:`run_model_checks`)."""
    out = []
    for a in arrays:
        if isinstance(a, np.ndarray):  # numbers are immutable: passed as they are
            a = np.array(a, copy=True)
            a.flags.writeable = False
        out.append(a)
    return out


def mueller_of(model, *angles, **kw):
    """``model.mueller(*angles, **kw)`` with read-only copies of the angles (:func:`readonly`)."""
    return model.mueller(*readonly(*angles), **kw)


def jones_of(model, *angles):
    """``model.jones(*angles)`` with read-only copies of the angles (:func:`readonly`)."""
    return model.jones(*readonly(*angles))


def evaluate(model, ti, tr, pr, **kw):
    """``(M, warned)``: ``model.mueller(ti, tr, pr, **kw)`` (read-only copies of the angles) as
    an array and the number of floating-point warnings it raised (gradual underflow, the
    correct IEEE result for far tails, not counted)."""
    with fp_warnings() as caught:
        M = np.asarray(mueller_of(model, ti, tr, pr, **kw))
    return M, len(caught)


def where(ti, tr, pr, k=None):
    """The geometry ``k`` of flat angle arrays (or scalars) in degrees."""
    if k is not None:
        ti, tr, pr = (np.asarray(a).reshape(-1)[k] for a in (ti, tr, pr))
    d = math.degrees
    return f"theta_i={d(float(ti)):.6g} deg, theta_r={d(float(tr)):.6g} deg, phi_r={d(float(pr)):.6g} deg"


def accepted_reason(model, kind, fields, accepted=None):
    """``(reason, condition)`` of the accepted finding (``accepted_findings.toml``, or the
    entries ``accepted``) that explains a ``kind`` of finding with these numeric ``fields``
    on one of scatterbench's own models, else ``None``: only scatterbench's models carry
    accepted findings."""

    if not type(model).__module__.startswith("scatterbench.models."):
        return None
    f = Finding(type(model).__name__, repr(model), kind, float(fields.get("value", math.nan)), "", fields)
    entry = edge_sweep.accepted_entry(f, accepted)
    return None if entry is None else (entry["reason"], entry.get("condition") or "always")


def finding_of(reason, condition) -> Finding:
    """The :class:`~scatterbench.validation.studies.findings.Finding` of a result an accepted
    finding explains: it holds (``fails=False``) and would fail if its accepted condition did not."""
    head = " ".join(reason.split())
    return Finding(fails=False, fails_if=f"the accepted condition `{condition}` does not hold ({head})")
