"""Validate your own model: the conformance kit (``check_model``, ``parametrize_with_checks``).

Any object with ``mueller(theta_i, theta_r, phi_r)`` that broadcasts numpy arrays (radians)
and returns ``(..., 4, 4)`` Mueller matrices in 1/sr, in the psps basis of DESIGN.md, is a
model; it need not import scatterbench.  The kit runs every conformance check on it and
names what fails, with the measured value, the limit and the worst geometry::

    from scatterbench.validation.testing import check_model
    report = check_model(MyBRDF())
    print(report)            # the table; report.passed, report.results

and in a test suite, one test per (model, check)::

    from scatterbench.validation.testing import parametrize_with_checks

    @parametrize_with_checks([MyBRDF(), MyBRDF(roughness=0.5)])
    def test_conformance(model, check):
        check(model)

The checks (:func:`scatterbench.validation.checks.conformance.conformance_checks`): ``broadcasting``
(scalar, 0-d, array, broadcast and chunked calls agree), ``dtypes`` (float32 and integer
angles), ``out_argument`` (``out=``, if ``mueller`` takes one), ``finite`` and
``nonnegative`` (M00 >= 0) on a grid of extreme geometries, ``realizable`` (coherency
eigenvalues), ``reciprocity`` (M00, Mueller and, with ``jones``, Jones), ``energy`` (integrated reflectance at a
ladder of incidences), ``determinism`` (the same seed gives the same numbers),
``pickle``, ``parameter_extremes`` (a :class:`scatterbench.models.Model`'s declared parameters at their
edges) and ``scatmech`` (agreement with an equivalent SCATMECH model).  A check that needs
a capability the model does not have is skipped with a note, not failed.

Optional attributes a model may set (:data:`ATTRIBUTES`): ``reciprocal``, ``energy_bound``,
``stochastic``, ``seed``, ``scatmech``, ``transmission``, ``jones``, ``rotated``, ``lobe``,
``mirror_symmetric``.  A :class:`scatterbench.models.Model` subclass has most of them already.

Models other packages register in the ``scatterbench.models`` entry-point group
(:func:`contributed_models`) appear in ``scatterbench models``, the stability sweep and the
report's contributed-models section (:func:`contributed_section`).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from scatterbench import models
from scatterbench.models.contributed import ENTRY_POINT_GROUP, Contributed, contributed_models, resolve
from scatterbench.validation.checks.conformance import (
    ATTRIBUTES,
    ModelCheck,
    conformance_checks,
    run_model_checks,
)
from scatterbench.validation.checks.registry import CheckContext, check_record, tally

__all__ = [
    "ATTRIBUTES",
    "ModelCheck",
    "ModelReport",
    "check_model",
    "parametrize_with_checks",
    "load_model",
    "Contributed",
    "contributed_models",
    "format_contributed",
    "shipped_models",
    "ContributedRow",
    "contributed_section",
]

#: the entry-point group other packages register their models in


@dataclass(frozen=True)
class ModelReport:
    """The conformance results of one model: ``passed`` is True when no check failed
    (findings explained by an accepted finding and skipped checks do not fail)."""

    model: str
    results: tuple[ModelCheck, ...]

    @property
    def passed(self) -> bool:
        return not self.failures

    @property
    def failures(self) -> list[ModelCheck]:
        return [r for r in self.results if r.status == "fail"]

    def summary(self) -> dict:
        """Counts: ``n_checks``, ``n_pass``, ``n_finding``, ``n_fail``, ``n_skip``."""
        n = tally(self.results)
        n["n_skip"] = n["n_checks"] - n["n_pass"] - n["n_finding"] - n["n_fail"]
        return n

    def as_dict(self) -> dict:
        """Strict-JSON-ready: the model, ``passed``, the summary and every result (its
        fields, ``where`` the worst geometry, and its one-line ``message``)."""
        return {
            "model": self.model,
            "passed": self.passed,
            "summary": self.summary(),
            "results": [{**check_record(r), "message": r.message} for r in self.results],
        }

    def format(self) -> str:
        """The table ``scatterbench check`` prints."""
        w = max([len(r.name) for r in self.results] + [5])
        lines = [f"{self.model}", f"{'check':<{w}}  {'measured':>11}  {'limit':>12}  status", "-" * (w + 40)]
        for r in self.results:
            measured = "" if r.status == "skip" else f"{r.measured:.4g}"
            limit = "" if r.status == "skip" else f"{r.op} {r.tolerance:.4g}"
            lines.append(f"{r.name:<{w}}  {measured:>11}  {limit:>12}  {r.status.upper()}")
            if r.where and r.status in ("fail", "finding"):
                lines.append(f"{'':<{w}}    worst at {r.where}")
            if r.detail:
                lines.append(f"{'':<{w}}    {r.detail}")
        n = self.summary()
        lines.append(
            f"{n['n_checks']} results: {n['n_pass']} pass, {n['n_finding']} findings, "
            f"{n['n_fail']} fail, {n['n_skip']} skipped"
        )
        return "\n".join(lines)

    __str__ = format


def check_model(model, *, checks=None, quick=False, label=None, ctx=None) -> ModelReport:
    """Run every applicable conformance check on ``model``.

    Parameters
    ----------
    model : object
        Anything with ``mueller(theta_i, theta_r, phi_r)`` (see the module docstring).
    checks : sequence of str, optional
        The checks to run, by name (default: all, in their registered order).
    quick : bool
        Skip the slow checks (``parameter_extremes``) and shorten the energy ladder to
        normal and grazing incidence.
    label : str, optional
        The model's name in the results (default: its class name).
    ctx : validation.checks.registry.CheckContext, optional
        A context whose memo is shared (e.g. with a report); its quick flag must be ``quick``.

    Returns
    -------
    ModelReport

    Examples
    --------
    >>> from scatterbench import models
    >>> from scatterbench.validation.testing import check_model
    >>> report = check_model(models.FacetBRDF(), checks=["reciprocity"])
    >>> [(r.name, r.status) for r in report.results]
    [('reciprocity: M00', 'pass'), ('reciprocity: Mueller', 'pass'), ('reciprocity: Jones', 'pass')]
    """
    if not callable(getattr(model, "mueller", None)):
        raise ValueError(f"model must have a mueller(theta_i, theta_r, phi_r) method; got {model!r}")
    ctx = ctx if ctx is not None else CheckContext(quick=quick)
    if ctx.quick != bool(quick):
        raise ValueError(f"ctx: its quick flag ({ctx.quick}) must be the run's ({quick})")
    label = label or type(model).__name__
    specs = conformance_checks(checks)
    return ModelReport(label, tuple(run_model_checks(model, ctx, specs, label)))


class _Check:
    """One conformance check bound to a run; ``check(model)`` asserts it (pytest)."""

    def __init__(self, spec, label, ctx):
        self.spec, self.label, self.ctx = spec, label, ctx

    def __repr__(self):
        return self.spec.name

    def __call__(self, model):
        import pytest  # pytest (optional: the kit's pytest helpers only)

        results = run_model_checks(model, self.ctx, [self.spec], self.label)
        failed = [r.message for r in results if r.status == "fail"]
        if failed:
            raise AssertionError("\n".join(failed))
        if all(r.status == "skip" for r in results):
            pytest.skip("; ".join(r.detail for r in results))
        found = [r.message for r in results if r.status == "finding"]
        if found:
            pytest.xfail("accepted finding: " + "; ".join(found))


def _labels(models_, ids):
    if ids is not None:
        if len(ids) != len(models_):
            raise ValueError(f"ids must name each of the {len(models_)} models; got {len(ids)}")
        return list(ids)
    names = [type(m).__name__ for m in models_]
    return [n if names.count(n) == 1 else f"{n}{names[:i].count(n) + 1}" for i, n in enumerate(names)]


def parametrize_with_checks(models_, *, checks=None, quick=False, ids=None):
    """A ``pytest.mark.parametrize("model, check", ...)`` with one test per (model, check),
    ids ``"<model>-<check>"``; the test body is ``check(model)``.

    A failed check raises ``AssertionError`` with its message (check, measured value, limit,
    worst geometry); a skipped one calls ``pytest.skip`` with its note; one an accepted
    finding explains calls ``pytest.xfail`` with the finding's reason.  ``checks``, ``quick``:
    as :func:`check_model`; ``ids``: the models' names (default: class names, numbered when
    repeated).
    """
    import pytest  # pytest (optional: the kit's pytest helpers only)

    models_ = list(models_)
    ctx = CheckContext(quick=quick)  # shared: the grid evaluations of a model run once
    specs = conformance_checks(checks)
    params, names = [], []
    for label, model in zip(_labels(models_, ids), models_, strict=True):
        for spec in specs:
            params.append((model, _Check(spec, label, ctx)))
            names.append(f"{label}-{spec.name}")
    return pytest.mark.parametrize("model, check", params, ids=names)


# --------------------------------------------------------------------------- finding models
def load_model(spec: str):
    """The model ``MODULE:NAME`` names: an instance, or a class or callable returning one.

    Parameters
    ----------
    spec : str
        ``"module:name"``; ``name`` may be dotted (an attribute of an attribute).

    Returns
    -------
    object
        The model (it has a ``mueller`` method).

    Raises
    ------
    ValueError
        Naming ``spec``, when the module or the name is not found, importing or calling it
        raises, or the object is not a model.
    """
    module, sep, name = spec.partition(":")
    if not sep or not module or not name:
        raise ValueError(f"model must be MODULE:NAME (e.g. mypkg.brdf:MyModel); got {spec!r}")
    try:
        obj = importlib.import_module(module)
    except ImportError as exc:
        raise ValueError(f"model {spec!r}: module {module!r} not found ({exc})") from exc
    except Exception as exc:  # noqa: BLE001 - a module that fails to import is a bad argument here
        raise ValueError(f"model {spec!r}: importing {module!r} raised {type(exc).__name__}: {exc}") from exc
    for part in name.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"model {spec!r}: {module!r} has no attribute {name!r}")
        obj = getattr(obj, part)
    return resolve(obj, f"model {spec!r}")


def format_contributed(contributed=None) -> str:
    """The contributed models as ``scatterbench models`` lists them: entry name, ``module:attr``,
    distribution, and the model's parameters (a :class:`scatterbench.models.Model`) or docstring summary."""
    entries = contributed_models() if contributed is None else contributed
    lines = [f"\nContributed models (entry-point group {ENTRY_POINT_GROUP}): {len(entries) or 'none'}"]
    for c in entries:
        lines.append(f"\n{c.name} = {c.value}  [{c.dist}]")
        if c.model is None:
            lines.append(f"    not loaded: {c.error}")
        elif isinstance(c.model, models.Model):
            lines.append("    " + type(c.model).info().replace("\n", "\n    "))
        else:
            doc = (type(c.model).__doc__ or "").strip().splitlines()
            lines.append(f"    {type(c.model).__name__}: {doc[0] if doc else repr(c.model)}")
    return "\n".join(lines)


def shipped_models() -> list[tuple[str, object]]:
    """``(label, model)``: one instance of every model class scatterbench ships, as its own
    test suite checks them.

    Each class's stability-sweep representative (``Cls.sweep_base()``: its defaults, or for
    a wrapper a representative inner model) with the changes the class names in its
    ``kit_variant``: a cheaper instance that tests the same code (``RoughDiffuseBRDF`` with
    20 Monte Carlo pairs, ``PointSourceBRDF`` with 4 radial nodes), or the parameters of
    committed SCATMECH reference values, so that the ``scatmech`` check compares with them
    where pySCATMECH is not installed (``FacetBRDF``, ``SubsurfaceFacetBRDF``, ``FacetBTDF``).

    Where a default is a paper's known slip (``CookTorranceBRDF``'s published
    normalization, ``FacetBTDF``'s Eq. 37), the kit reports a finding with the reason
    ``accepted_findings.toml`` gives.
    """
    out = []
    for cls in models.Model.registry:
        base = cls.sweep_base()
        if base is None:
            continue  # compositions (Sum): their terms are the other models
        out.append((cls.__name__, base.replace(**cls.kit_variant)))
    return out


# --------------------------------------------------------------------------- report data
@dataclass(frozen=True)
class ContributedRow:
    """One contributed model in the report: entry name, distribution, ``module:attr``, the
    model's repr, and its conformance (``None`` with ``error`` when it did not load)."""

    name: str
    dist: str
    value: str
    model: str
    report: dict | None
    error: str | None = None


def contributed_section(ctx, contributed=None) -> list[ContributedRow]:
    """The data of the report's contributed-models section: every entry point's model with
    its conformance results.

    Parameters
    ----------
    ctx : validation.checks.registry.CheckContext
        The report's context: a quick report runs the quick kit, and the results stay in
        its memo.
    contributed : list of Contributed, optional
        The entries (default: :func:`contributed_models`).

    Returns
    -------
    list of ContributedRow
        One per entry, in name order; ``report`` is :meth:`ModelReport.as_dict` (``None``
        with ``error`` for an entry that did not load).
    """
    rows = []
    for c in contributed_models() if contributed is None else contributed:
        if c.model is None:
            rows.append(ContributedRow(c.name, c.dist, c.value, "", None, c.error))
            continue
        rep = check_model(c.model, quick=ctx.quick, label=c.name, ctx=ctx)
        rows.append(ContributedRow(c.name, c.dist, c.value, _short(repr(c.model)), rep.as_dict()))
    return rows


def _short(text, n=160):
    return text if len(text) <= n else text[: n - 3] + "..."
