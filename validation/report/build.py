"""Compute every section, render one self-contained HTML page and results.json."""

from __future__ import annotations

import datetime
import json
import os
import sys
import time
import traceback

from validation.atomic import atomic_write_json, atomic_write_text
from validation.checks.registry import SEED, check_record, judge, select, tally

from .core import Context, Section, render_html
from .sections import SECTION_FUNCS, _git_commit, report_checks

__all__ = ["build_report", "write_report", "read_results", "read_results_checked"]


def _progress(total, label):
    """A tqdm bar on a terminal; silent in CI or when stderr is not a terminal."""
    from tqdm import tqdm

    quiet = bool(os.environ.get("CI")) or not sys.stderr.isatty()
    return tqdm(total=total, desc=label, disable=quiet, unit="section", leave=False)


def _section_failure(name):
    """A section that raised, as a failed entry of the report machinery (not a registered check)."""
    r = judge(
        f"report section '{name}' computed",
        1.0,
        0.0,
        "the report machinery: this section raised\n" + traceback.format_exc(limit=3),
    )
    return {**check_record(r), "id": f"report.section_{name}", "paper": "report machinery"}


def _context(context, quick, previous, seed):
    if context is None:
        return Context(quick=quick, previous=previous, seed=seed)
    if (context.quick, context.seed) != (quick, seed):
        raise ValueError(
            f"context: quick={context.quick}, seed={context.seed} must be the report's ({quick}, {seed})"
        )
    context.previous = previous
    return context


def _run_sections(ctx, funcs):
    """Compute ``funcs`` (summary last: it shows every check and failure); a section
    that raises is kept with its error and recorded in ``ctx.cache["section_failures"]``."""
    order = [f for f in funcs if f.__name__ not in ("section_summary", "section_provenance")]
    order += [f for f in funcs if f.__name__ == "section_provenance"]
    order += [f for f in funcs if f.__name__ == "section_summary"]
    done = {}
    times = ctx.cache.setdefault("section_times", {})
    failures = ctx.cache.setdefault("section_failures", [])
    with _progress(len(order), "report") as bar:
        for fn in order:
            name = fn.__name__.removeprefix("section_")
            bar.set_postfix_str(name)
            t = time.perf_counter()
            try:
                sec = fn(ctx)
            except Exception as exc:  # a broken section must not lose the rest of the report
                sec = Section(name, name, error=f"{type(exc).__name__}: {exc}")
                sec.blocks = []
                failures.append(_section_failure(name))
            sec.seconds = time.perf_counter() - t
            times[name] = sec.seconds
            done[fn.__name__] = sec
            bar.update(1)
    return [done[f.__name__] for f in funcs]


def build_report(
    quick=False, previous=None, seed=SEED, only=None, extra_scenes=(), checks=None, context=None
):
    """Run every section; returns ``(results, html)``.  A section that raises is kept
    on the page with its error and counts as a failed check; the others still run.

    ``only``: names of the sections to compute (summary and provenance always run);
    ``extra_scenes``: scene files shown beside the built-in examples;
    ``checks``: ids of the registered checks the summary judges (default: every one,
    less the slow ones in a quick run: the set ``validate`` judges);
    ``context``: a :class:`~validation.report.core.Context` to run in (its memo shared,
    e.g. with ``validate``); default a new one.
    """
    ctx = _context(context, quick, previous, seed)
    ctx.cache["extra_scenes"] = list(extra_scenes)
    if checks is not None:
        ctx.cache["check_specs"] = select(checks)
    t0 = time.perf_counter()
    funcs = [
        f
        for f in SECTION_FUNCS
        if only is None or f.__name__.removeprefix("section_") in set(only) | {"summary", "provenance"}
    ]
    sections = _run_sections(ctx, funcs)
    # every check is counted even if the summary section itself failed to draw them
    checks = report_checks(ctx) + ctx.cache["section_failures"]
    summary = tally(checks)
    meta = {
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "git_commit": _git_commit(),
        "quick": quick,
        "seed": seed,
        "seconds": time.perf_counter() - t0,
    }
    results = {
        "meta": meta,
        "summary": summary,
        "checks": checks,
        "sections": {s.id: s.as_json() for s in sections},
    }
    # round-trip through JSON so the page is rendered from exactly what results.json holds
    results = json.loads(json.dumps(results, default=float))
    html = render_html(meta, sections, summary)
    return results, html


def read_results_checked(path):
    """``(results, problem)`` of a results.json: ``(dict, None)`` when it holds a report's
    results; ``(None, None)`` when there is no such file; ``(None, why)`` when it cannot
    be used (unreadable, not JSON, not a results object)."""
    if not os.path.lexists(path):
        return None, None
    try:
        with open(path, encoding="utf-8") as fh:
            res = json.load(fh)
    except OSError as exc:
        return None, f"{path}: cannot be read ({exc.strerror})"
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, bad UTF-8, too deeply nested
        return None, f"{path}: not valid JSON ({exc})"
    if not isinstance(res, dict) or not isinstance(res.get("checks"), list):
        return None, f"{path}: not a report's results (an object with a list of checks)"
    return res, None


def read_results(path):
    """The results in ``path``, or ``None`` when there are none that can be used."""
    return read_results_checked(path)[0]


def write_report(out_dir, quick=False, previous=None, **kwargs):
    """Write ``report.html`` and ``results.json`` into ``out_dir`` (each atomically).

    The previous ``results.json`` of that folder (if any) is the comparison base
    for "change since previous" unless ``previous`` is given; one that cannot be
    used is said so in ``results["meta"]["previous_problem"]``.
    """
    os.makedirs(out_dir, exist_ok=True)
    problem = None
    if previous is None:
        previous, problem = read_results_checked(os.path.join(out_dir, "results.json"))
    results, html = build_report(quick=quick, previous=previous, **kwargs)
    if problem:
        results["meta"]["previous_problem"] = problem
    atomic_write_json(os.path.join(out_dir, "results.json"), results)
    atomic_write_text(os.path.join(out_dir, "report.html"), html)
    return results
