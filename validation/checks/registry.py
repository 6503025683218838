"""The check registry: one declaration feeds ``scatterbench validate``, the report and pytest.

A check is a function ``f(ctx, **inputs)`` declared once with :func:`check`; it
returns one :class:`Check` or a list of them, each made by :func:`judge`, the
one place a (measured, tolerance) pair becomes a status:

* ``pass``: the measured value is within the limit it is shown with;
* ``fail``: it is not, it is not finite, or a finding's stated failure
  condition holds;
* ``finding``: a property *of a paper* that the run established (e.g. a
  printed Table I entry that an independent calculation contradicts).  Every
  finding states, as ``fails if: ...``, the condition under which it would
  instead fail, computed from what the check measured.

Checks take their inputs as keyword parameters with defaults (so a test can hand
one a broken model or quantity) and a context, :class:`CheckContext`: the quick
flag, the seed, and a memo through which an expensive computation (the stability
sweep, the model-comparison fits, the recovery study) runs once per run and is
shared with the report section that draws it.  Slow checks are skipped by quick
runs (``validate --quick`` and ``report --quick`` judge the same set).

The text blocks ``validate`` prints after its table are registered here too,
with :func:`text_section`.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import threading
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field

from scatterbench.validation.fitting.executors import SerialExecutor
from scatterbench.validation.studies.findings import Finding

__all__ = [
    "Check",
    "judge",
    "check",
    "CheckSpec",
    "CheckContext",
    "registered",
    "select",
    "run_checks",
    "format_checks",
    "tally",
    "check_record",
    "text_section",
    "texts",
    "SEED",
]

#: the run seed of ``validate`` and ``report`` (fits and studies draw from it)
SEED = 20261122

#: comparison operators a limit may use: ``measured OP tolerance`` is "within"
_OPS = {"<=": operator.le, "<": operator.lt, ">=": operator.ge, ">": operator.gt}


@dataclass(frozen=True)
class Check:
    """One result: ``status`` is ``measured op tolerance`` judged by :func:`judge`."""

    name: str
    measured: float
    tolerance: float
    status: str  # "pass", "fail" or "finding"
    detail: str = ""
    op: str = "<="
    fails_if: str | None = None  # set on every result of a finding-type check
    id: str = ""  # the registered check that returned it (set by run_checks)
    paper: str = ""
    slow: bool = False

    def as_dict(self):
        return dataclasses.asdict(self)


def judge(name, measured, tolerance, detail="", *, op="<=", finding=None) -> Check:
    """The status of ``measured op tolerance``: the only place a status is decided.

    Parameters
    ----------
    name : str
        The check's name (tracked across nights by name: keep it stable).
    measured, tolerance : float
        What the run measured and the limit it is held to; a non-finite measured
        value fails.
    detail : str
        What was measured and how.
    op : {"<=", "<", ">=", ">"}
        ``measured op tolerance`` is within the limit.
    finding : Finding, optional
        For a finding-type result (:class:`~scatterbench.validation.studies.findings.Finding`
        with its verdict, ``fails`` and ``fails_if``): outside the limit is a ``finding`` (a
        property of the paper), unless ``finding.fails``; within the limit is a ``pass``.

    Returns
    -------
    Check
    """
    if op not in _OPS:
        raise ValueError(f"op must be one of {', '.join(_OPS)}; got {op!r}")
    if finding is not None and not isinstance(finding, Finding):
        raise ValueError(f"finding must be a Finding or None; got {type(finding).__name__}")
    if finding is not None and (finding.fails is None or finding.fails_if is None):
        raise ValueError(f"a check's finding states its verdict, fails and fails_if; got {finding!r}")
    m, t = float(measured), float(tolerance)
    within = math.isfinite(m) and bool(_OPS[op](m, t))
    if not math.isfinite(m) or (finding is not None and finding.fails):
        status = "fail"
    elif within:
        status = "pass"
    else:
        status = "finding" if finding is not None else "fail"
    return Check(name, m, t, status, detail, op, finding.fails_if if finding is not None else None)


@dataclass(frozen=True)
class CheckSpec:
    """A registered check: ``id`` is ``module.function`` below ``validation.checks``.

    ``findings``: the names of the results that are finding-type (may be
    ``finding`` rather than ``pass``; each must carry a
    :class:`~scatterbench.validation.studies.findings.Finding`).
    """

    id: str
    func: Callable
    paper: str
    slow: bool = False
    findings: tuple[str, ...] = ()


_CHECKS: dict[str, CheckSpec] = {}
_TEXTS: list[Callable] = []


def check(*, paper, slow=False, findings=()):
    """Register a check function ``f(ctx, **inputs) -> Check | list[Check]``.

    Parameters
    ----------
    paper : str
        The paper, equation or section the check tests (e.g. ``"seed 000 Eq. A.2-A.4"``).
    slow : bool
        Skipped by quick runs (``validate --quick``, ``report --quick``).
    findings : sequence of str
        Names of the finding-type results the check returns.
    """
    if not paper:
        raise ValueError("paper must name the paper, equation or section the check tests")

    def register(fn):
        cid = f"{fn.__module__.removeprefix('scatterbench.validation.checks.')}.{fn.__name__}"
        _CHECKS[cid] = CheckSpec(cid, fn, paper, bool(slow), tuple(findings))
        return fn

    return register


def registered(quick=False):
    """The registered checks in run order; ``quick`` leaves out the slow ones.  (This module
    is imported through its package, whose ``__init__`` imports every check module first: the
    registry is complete whenever it can be read.)"""
    return [s for s in _CHECKS.values() if not (quick and s.slow)]


def select(ids):
    """The registered checks with these ids (``ValueError`` naming an unknown one)."""
    specs = {s.id: s for s in registered()}
    unknown = [i for i in ids if i not in specs]
    if unknown:
        raise ValueError(f"checks: unknown id(s) {', '.join(unknown)}; registered: {', '.join(specs)}")
    return [specs[i] for i in ids]


#: one lock per memo entry being computed: a report computes some sections at once, on
#: threads (:func:`scatterbench.validation.report.build.build_report`), and two of them asking
#: for one study must share one run of it, not each start their own
_COMPUTING: dict = {}
_COMPUTING_GUARD = threading.Lock()


def _once(memo, key, make):
    """``memo[key]``, made by ``make()`` the first time: by one thread, the others asking for
    it meanwhile waiting for its value (a failed ``make`` raises in each, and the next asks again)."""
    if key in memo:
        return memo[key]
    with _COMPUTING_GUARD:
        lock = _COMPUTING.setdefault((id(memo), key), threading.Lock())
    with lock:
        try:
            if key not in memo:
                memo[key] = make()
            return memo[key]
        finally:
            with _COMPUTING_GUARD:
                _COMPUTING.pop((id(memo), key), None)


@dataclass
class CheckContext:
    """What a run gives its checks: the quick flag, the seed, a memo and an executor.

    :meth:`compute` runs ``fn(*args, **kw)`` once per run and context; the
    report's context is one, so a section reuses what a check computed.
    :meth:`study` does the same for a study that runs on the run's ``executor``
    (:mod:`scatterbench.validation.fitting.executors`; ``None``: in-process), whose
    results do not depend on it.
    """

    quick: bool = False
    seed: int = SEED
    memo: dict = field(default_factory=dict)
    executor: object = None

    def compute(self, fn, *args, **kw):
        """``fn(*args, **kw)``, computed once per context (arguments must be hashable);
        the result is shared: treat it as read-only."""
        key = (fn.__module__, fn.__qualname__, args, tuple(sorted(kw.items())))
        return _once(self.memo, key, lambda: fn(*args, **kw))

    def study(self, fn, *args, **kw):
        """``fn(*args, executor=..., **kw)`` on the run's executor, computed once per context
        like :meth:`compute` and keyed without the executor: a study gives the same results on
        any executor (benchmarks/study_workers.py, tests/test_report_executors.py)."""
        key = (fn.__module__, fn.__qualname__, args, tuple(sorted(kw.items())))
        return _once(self.memo, key, lambda: fn(*args, executor=self.runner(), **kw))

    def runner(self):
        """The run's executor (in-process when none was given)."""
        return self.executor if self.executor is not None else SerialExecutor()


def _broken(spec, name, why):
    r = judge(name, math.nan, math.nan, why)
    return dataclasses.replace(r, id=spec.id, paper=spec.paper, slow=spec.slow)


def _declared(spec, r):
    """``r`` with the registry's id, paper and slow flag; a finding-type result the
    registration does not declare (or a declared one without its Finding) fails."""
    r = dataclasses.replace(r, id=spec.id, paper=spec.paper, slow=spec.slow)
    if (r.name in spec.findings) != (r.fails_if is not None):
        why = "declared a finding without a Finding" if r.fails_if is None else "undeclared finding"
        r = dataclasses.replace(r, status="fail", detail=f"{why} ({spec.id}); {r.detail}")
    return r


def _run_one(spec, ctx):
    try:
        out = spec.func(ctx)
    except Exception as exc:  # noqa: BLE001 - any error is this check's failure, not the run's
        tb = traceback.format_exc(limit=2).strip().splitlines()[-1]
        return [_broken(spec, spec.func.__name__, f"raised {type(exc).__name__}: {exc} [{tb}]")]
    out = out if isinstance(out, list) else [out]
    if not out or not all(isinstance(r, Check) for r in out):
        return [_broken(spec, spec.func.__name__, "returned no Check")]
    return [_declared(spec, r) for r in out]


def run_checks(specs=None, ctx=None):
    """Every result of ``specs`` (default: every registered check for ``ctx.quick``).

    A check that raises is a failed result named after its function, so one broken
    check cannot empty the summary.  Results are kept in ``ctx.memo``: a check runs
    once per context.
    """
    ctx = ctx if ctx is not None else CheckContext()
    specs = registered(ctx.quick) if specs is None else specs
    out = []
    for spec in specs:
        out.extend(_once(ctx.memo, ("check", spec.id), lambda spec=spec: _run_one(spec, ctx)))
    return out


def tally(results):
    """``{"n_checks", "n_pass", "n_finding", "n_fail"}`` of results (Checks or records)."""
    status = [r["status"] if isinstance(r, dict) else r.status for r in results]
    return {
        "n_checks": len(status),
        "n_pass": status.count("pass"),
        "n_finding": status.count("finding"),
        "n_fail": status.count("fail"),
    }


def check_record(r):
    """The JSON record of a result: id, name, paper, measured, tolerance, op, status,
    detail, fails_if (``None`` unless finding-type), slow; non-finite numbers as ``None``."""
    d = r.as_dict()
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


def _limit(r, width):
    t = f"{r.tolerance:.3g}"
    return f"{t:>{width}}" if r.op == "<=" else f"{r.op + ' ' + t:>{width}}"


def format_checks(results) -> str:
    """The table ``validate`` prints: name, measured, limit, status, detail, fails if."""
    w = max(len(c.name) for c in results)
    lines = [f"{'check':<{w}}  {'measured':>11}  {'tolerance':>10}  status", "-" * (w + 36)]
    for c in results:
        lines.append(f"{c.name:<{w}}  {c.measured:>11.3g}  {_limit(c, 10)}  {c.status.upper()}")
        if c.detail:
            lines.append(f"{'':<{w}}    {c.detail}")
        if c.fails_if:
            lines.append(f"{'':<{w}}    fails if: {c.fails_if}")
    n = tally(results)
    lines.append(f"{n['n_checks']} checks: {n['n_pass']} pass, {n['n_finding']} findings, {n['n_fail']} fail")
    return "\n".join(lines)


def text_section(fn):
    """Register ``fn(ctx) -> (title, text) | None``, printed by ``validate`` after its table."""
    _TEXTS.append(fn)
    return fn


def texts():
    """The registered text sections, in order."""
    return list(_TEXTS)
