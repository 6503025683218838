"""Stability sweep: every model at the edges of its parameter space and geometry.

For each public model class (``models.Model.registry``), and each model another package
contributes (``scatterbench.models`` entry points, :func:`scatterbench.models.contributed.contributed_models`),
the sweep builds instances at the edges of each declared parameter, one parameter at a time
from the defaults (nested declared objects, such as slope distributions, are
swept the same way), and evaluates them on edge geometries: polar angles 0,
1e-9, 89.99 deg and exactly 90 deg, exact specular and retroreflection, the
critical angle of each interface +- 1e-9, azimuths 0, +-pi and +-1e-12, and the
same angles as float32.  It records

* ``fp-warning``: a floating-point warning (division by zero, overflow, invalid
  operation; gradual underflow to zero is the correct IEEE result for far
  tails and is not counted),
* ``non-finite``: a NaN or inf in the Mueller (or Jones) matrix,
* ``negative-M00``: a negative BRDF,
* ``unphysical``: a coherency-matrix eigenvalue below ``-1e-9 M00``,
* ``reciprocity``: a relative violation above 1e-9 (reciprocal models),
* ``energy``: an integrated reflectance above ``1 + error`` at 0, 57 or 89.99 deg,
  ``energy-unresolved`` where that integral did not reach its tolerance within
  the evaluation budget (the check would otherwise be vacuous).

Findings that physics explains are listed, each with its reason, in
``accepted_findings.toml`` beside this module; anything else is a failure of
``scatterbench stability`` and of the test suite.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import os
import threading
import tomllib
from dataclasses import dataclass

import numpy as np

from scatterbench import models
from scatterbench.models.contributed import as_model, contributed_models
from scatterbench.models.params import Declared
from scatterbench.models.polarization import coherency_eigenvalues
from scatterbench.validation.fitting.executors import SerialExecutor
from scatterbench.validation.numerics.energy import hit_fraction
from scatterbench.validation.numerics.integrate import integrated_reflectance
from scatterbench.validation.numerics.probes import fp_warnings
from scatterbench.validation.numerics.reciprocity import reciprocity_error

from .findings import Finding

__all__ = [
    "edge_instances",
    "edge_geometries",
    "sweep",
    "sweep_model",
    "load_accepted",
    "classify",
    "FindingGroup",
    "group_findings",
    "format_sweep",
]

ACCEPTED_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "accepted_findings.toml")

# What is swept is each class's own: the edge values of its declared parameters
# (models.params.param's ``edges``, else the constraint's), its representative instance
# (``Cls.sweep_base()``) and the instances its edges do not reach (``Cls.sweep_extras()``).


def _edges_for(info, current):
    """The values ``info``'s parameter is swept at from ``current``: its declared edges, or
    for a declared object without them (a slope distribution, a phase function, an inner
    model) that object's own variants, one parameter at a time."""
    if info.declared_edges is None and info.kind == "object" and isinstance(current, Declared):
        return [inst for inst in _one_at_a_time(current) if inst != current]
    return info.edges(current)


def _one_at_a_time(base, names=None):
    """``base`` and its variants, one parameter (of ``names``; default all) at its edges."""
    out = [base]
    for info in type(base).parameters():
        if names is not None and info.name not in names:
            continue
        default = getattr(base, info.name)
        for value in _edges_for(info, default):
            try:
                out.append(dataclasses.replace(base, **{info.name: value}))
            except ValueError:
                continue  # outside this parameter's declared range (e.g. a real_index bound)
    return out


def _choice_combinations(base):
    """Every combination of the ``choice`` parameters (few: normalizations, methods)."""
    infos = [i for i in type(base).parameters() if i.choices is not None]
    out = []
    for combo in itertools.product(*(i.choices for i in infos)):
        try:
            out.append(dataclasses.replace(base, **{i.name: v for i, v in zip(infos, combo, strict=True)}))
        except ValueError:
            continue
    return out


def edge_instances(cls):
    """Model instances at the edges of each declared parameter (one at a time from the
    class's representative instance, ``cls.sweep_base()``, or from ``cls`` when it is a model
    instance), plus every combination of the choice parameters there, plus for a class the
    instances of ``cls.sweep_extras()`` swept at the edges of the parameters each names."""
    base = cls if isinstance(cls, models.Model) else cls.sweep_base()
    if base is None:
        return []  # compositions without a default (Sum): their terms are swept
    out = _one_at_a_time(base)
    for inst in _choice_combinations(base):
        if inst not in out:
            out.append(inst)
    if not isinstance(cls, models.Model):
        for extra, names in cls.sweep_extras():
            out += [inst for inst in _one_at_a_time(extra, names) if inst not in out]
    return out


def _real_indices(obj, out=None):
    out = [] if out is None else out
    if isinstance(obj, Declared):
        for info in type(obj).parameters():
            v = getattr(obj, info.name)
            if isinstance(v, models.FilmStack):  # its films' and substrate's indices
                films, sub = v.indices
                out += [float(n.real) for n in (*films, sub) if n != math.inf and n.imag == 0]
            elif isinstance(v, models.Films):  # films on the coating: their indices
                out += [float(n.real) for n in v.indices if n.imag == 0]
            elif info.kind in ("index", "real_index") and v != math.inf and complex(v).imag == 0:
                out.append(float(complex(v).real))
            elif isinstance(v, Declared):
                _real_indices(v, out)
    return out


def edge_geometries(model):
    """``(ti, tr, pr)`` flat arrays of edge geometries for one model."""
    d = math.radians
    thetas = [0.0, 1e-9, 0.5, 1.0, d(89.99), math.pi / 2 - 1e-9, math.pi / 2]
    idx = _real_indices(model)
    crit = set()
    for a in idx:
        if a > 1:
            crit.add(math.asin(1 / a))
        for b in idx:
            if b < a:
                crit.add(math.asin(b / a))
    for c in sorted(crit):
        thetas += [max(c - 1e-9, 0.0), min(c + 1e-9, math.pi / 2)]
    phis = [0.0, math.pi, -math.pi, math.pi / 2, 1e-12, math.pi - 1e-12]
    t = np.array(sorted(set(thetas)))
    ti, tr, pr = np.meshgrid(t, t, np.array(phis), indexing="ij")
    return ti.ravel(), tr.ravel(), pr.ravel()


def _label(ti, tr, pr):
    return f"ti={math.degrees(ti):.9g} deg, tr={math.degrees(tr):.9g} deg, phi={math.degrees(pr):.9g} deg"


def _evaluate(model, ti, tr, pr, found, name, params):

    with fp_warnings() as caught:
        M = model.mueller(ti, tr, pr)
        J = None if model.depolarizing else model.jones(ti, tr, pr)
        M32 = model.mueller(ti.astype(np.float32), tr.astype(np.float32), pr.astype(np.float32))
    for w in caught:
        found.append(Finding(name, params, "fp-warning", 1.0, str(w.message)))
    bad = ~np.all(np.isfinite(M), axis=(-1, -2))
    if J is not None:
        bad |= ~np.all(np.isfinite(J), axis=(-1, -2))
    bad |= ~np.all(np.isfinite(M32), axis=(-1, -2))
    if np.any(bad):
        k = int(np.argmax(bad))
        found.append(Finding(name, params, "non-finite", float(bad.sum()), _label(ti[k], tr[k], pr[k])))
        M = np.where(np.isfinite(M), M, 0.0)
    m00 = M[..., 0, 0]
    if np.any(m00 < 0):
        k = int(np.argmin(m00))
        found.append(Finding(name, params, "negative-M00", float(m00[k]), _label(ti[k], tr[k], pr[k])))
    live = m00 > 1e-250
    if np.any(live):
        ev = coherency_eigenvalues(M[live])[..., 0] / m00[live]
        if ev.min() < -1e-9:
            k = int(np.flatnonzero(live)[np.argmin(ev)])
            found.append(Finding(name, params, "unphysical", float(ev.min()), _label(ti[k], tr[k], pr[k])))
    return M


def _is_monte_carlo(model):
    return hasattr(model, "pairs") and hasattr(model, "seed")


def _check_reciprocity(model, ti, tr, pr, found, name, params):
    # Monte Carlo estimates are reciprocal only within their standard error; that is
    # tested statistically with the model (tests/test_seed003_mc.py), not here.
    if not model.reciprocal or _is_monte_carlo(model):
        return
    keep = (ti < math.pi / 2) & (tr < math.pi / 2)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
        r = reciprocity_error(model, ti[keep], tr[keep], pr[keep])
    worst = max(r.scalar, r.mueller, r.jones or 0.0)
    if not np.isfinite(worst) or worst > 1e-9:
        found.append(Finding(name, params, "reciprocity", float(worst), "edge geometries"))


def _scalar_params(model):
    """Declared scalar parameters (for accepted-finding conditions)."""
    out = {}
    for info in type(model).parameters():
        v = getattr(model, info.name)
        if isinstance(v, (str, bool, int, float)):
            out[info.name] = v
    return out


def model_hit_fraction(model, theta_i):
    """The hit fraction (:func:`scatterbench.validation.numerics.energy.hit_fraction`, an integral) of the
    model's slope distribution under its coating at ``theta_i``; ``None`` without slopes."""
    slopes = getattr(model, "slopes", None)
    if not isinstance(slopes, models.SlopeDistribution):
        return None
    return hit_fraction(slopes, theta_i, float(getattr(model, "coating", 1.0)))


def energy_fields(model, theta_i, value, error, bound=1.0, hit=True):
    """The fields of an energy finding that accepted-finding conditions read: ``excess``
    (``value`` above ``bound`` beyond its ``error``), ``value``, ``theta_i``, the model's
    declared scalar parameters and (``hit``, when it has slopes) :func:`model_hit_fraction`."""
    fields = {"excess": value - bound - error, "value": value, "theta_i": theta_i}
    if isinstance(model, Declared):
        fields.update(_scalar_params(model))
    h = model_hit_fraction(model, theta_i) if hit else None
    if h is not None:
        fields["hit_fraction"] = h
    return fields


def _check_energy(model, found, name, params):
    # Wrappers that average their inner model with normalized weights (the point
    # source's sum_k w_k = 1) have an albedo that is a weighted mean of the inner
    # model's albedos at the incidences they mix; the inner models are swept
    # themselves, and integrating a wrapper costs hundreds of inner evaluations
    # per point, so wrappers are not integrated here.
    if model.transmission or isinstance(getattr(model, "model", None), models.Model):
        return
    # A Monte Carlo integrand is noisy: the cubature's error estimate would be
    # meaningless; its energy is tested against its standard error with the model.
    if _is_monte_carlo(model):
        return
    for ti in (0.0, 1.0, math.radians(89.99)):
        with np.errstate(divide="ignore", over="ignore", invalid="ignore", under="ignore"):
            r = integrated_reflectance(model, ti, tol=1e-3, max_evaluations=2_000_000)
        if not r.converged:
            found.append(
                Finding(
                    name,
                    params,
                    "energy-unresolved",
                    r.error,
                    f"theta_i = {math.degrees(ti):.4g} deg",
                    _scalar_params(model),
                )
            )
            continue
        if r.value - 1.0 - r.error > 0:
            fields = energy_fields(model, ti, r.value, r.error)
            found.append(
                Finding(name, params, "energy", r.value, f"theta_i = {math.degrees(ti):.4g} deg", fields)
            )


#: The sweep records warnings with :func:`warnings.catch_warnings`, which swaps process-wide
#: state: two instances swept at once in one process (threads of a Dask worker) would
#: record each other's warnings, so within a process they take turns.
_SWEEP_LOCK = threading.Lock()


def sweep_model(inst, energy=True, name=None):
    """The findings of one model instance at its edge geometries, its reciprocity and
    (with ``energy``) its integrated reflectance (``name``: the model's name in them,
    default its class name); one task of :func:`sweep`."""
    found = []
    name, params = name or type(inst).__name__, repr(inst)
    with _SWEEP_LOCK:
        ti, tr, pr = edge_geometries(inst)
        _evaluate(inst, ti, tr, pr, found, name, params)
        _check_reciprocity(inst, ti, tr, pr, found, name, params)
        if energy:
            _check_energy(inst, found, name, params)
    return found


def _sweep_task(task, energy):
    name, inst = task
    return sweep_model(inst, energy, name)


def sweep(classes=None, energy=True, executor=None):
    """Run the sweep; returns every finding (accepted or not).

    Parameters
    ----------
    classes : list of type, optional
        Model classes (default every registered model class but :class:`scatterbench.models.Sum`,
        then the models other packages contribute, ``scatterbench.models`` entry
        points, under their entry-point names).
    energy : bool
        Integrate each instance's reflectance (the slow part).
    executor : optional
        Runs the instances, one task each (:mod:`scatterbench.validation.fitting.executors`;
        default in-process).  The findings, and their order, are the same on any
        executor: each instance is swept alone and they are collected in order.
    """

    targets = [(None, c) for c in classes] if classes is not None else _default_targets()
    tasks = [(name, inst) for name, cls in targets for inst in edge_instances(cls)]
    work = functools.partial(_sweep_task, energy=energy)
    per_instance = (executor or SerialExecutor()).map(work, tasks, tasks=len(tasks))
    return [f for found in per_instance for f in found]


def _default_targets():

    own = [(None, c) for c in models.Model.registry if c is not models.Sum]
    return own + [(c.name, as_model(c.model)) for c in contributed_models() if c.model is not None]


def load_accepted(path=ACCEPTED_PATH):
    """Accepted findings: ``[[accepted]]`` tables with model, kind, condition, reason."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    entries = data.get("accepted", [])
    for i, e in enumerate(entries):
        for key in ("model", "kind", "reason"):
            if not e.get(key):
                raise ValueError(f"{path}: accepted entry {i + 1} needs a non-empty '{key}'")
    return entries


def _matches(entry, f):
    if entry["model"] not in ("*", f.model) or entry["kind"] != f.kind:
        return False
    cond = entry.get("condition")
    if not cond:
        return True
    try:
        return bool(eval(cond, {"__builtins__": {}, "math": math}, dict(f.fields)))  # noqa: S307
    except NameError:
        return False


def accepted_entry(finding, accepted=None):
    """The first accepted entry (:func:`load_accepted`, or ``accepted``) that explains
    ``finding``, else ``None``."""
    accepted = load_accepted() if accepted is None else accepted
    return next((e for e in accepted if _matches(e, finding)), None)


def classify(findings, accepted=None):
    """Split findings into ``(accepted, unaccepted)``; accepted items carry their reason."""
    accepted = load_accepted() if accepted is None else accepted
    ok, bad = [], []
    for f in findings:
        entry = accepted_entry(f, accepted)
        (ok if entry else bad).append((f, entry["reason"] if entry else None))
    return ok, bad


@dataclass(frozen=True)
class FindingGroup:
    """The findings of one model and kind that share one verdict: how many, the worst
    (largest magnitude) with its parameters and geometry, and the accepted reason (None:
    unaccepted)."""

    model: str
    kind: str
    count: int
    worst: Finding
    reason: str | None


def group_findings(findings, accepted=None) -> list[FindingGroup]:
    """Findings grouped by (model, kind, reason), unaccepted groups first."""
    ok, bad = classify(findings, accepted)
    groups = {}
    for f, reason in ok + bad:
        groups.setdefault((f.model, f.kind, reason), []).append(f)
    out = [
        FindingGroup(model, kind, len(fs), max(fs, key=lambda f: abs(f.value)), reason)
        for (model, kind, reason), fs in groups.items()
    ]
    return sorted(out, key=lambda g: (g.reason is not None, g.model, g.kind))


def format_sweep(findings, accepted=None) -> str:
    groups = group_findings(findings, accepted)
    lines = [f"{'model':<22} {'kind':<13} {'count':>5} {'worst':>11}  status", "-" * 70]
    for g in groups:
        status = "ACCEPTED" if g.reason else "UNACCEPTED"
        lines.append(f"{g.model:<22} {g.kind:<13} {g.count:>5} {g.worst.value:>11.4g}  {status}")
        lines.append(f"    e.g. {g.worst.params} at {g.worst.where}")
        if g.reason:
            lines.append(f"    reason: {g.reason}")
    n_bad = sum(g.count for g in groups if g.reason is None)
    lines.append(f"{len(findings)} findings: {len(findings) - n_bad} accepted, {n_bad} unaccepted")
    return "\n".join(lines)
