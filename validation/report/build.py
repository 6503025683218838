"""Compute every section, render one self-contained HTML page and results.json."""

from __future__ import annotations

import contextlib
import contextvars
import datetime
import json
import os
import sys
import time
import traceback
from concurrent.futures import ThreadPoolExecutor, as_completed
from concurrent.futures import wait as wait_for

from tqdm import tqdm

from scatterbench.validation.atomic import atomic_write_json, atomic_write_text, replacing_folder
from scatterbench.validation.checks.registry import SEED, check_record, judge, select, tally

from .core import Context, Section, render_html
from .provenance import git_commit
from .sections import SECTIONS, report_checks

__all__ = ["build_report", "write_report", "write_files", "read_results_checked", "REPORT_FILES"]


def _progress(total, label):
    """A tqdm bar on a terminal; silent in CI or when stderr is not a terminal."""

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


def _context(context, quick, previous, seed, executor):
    if context is None:
        return Context(quick=quick, previous=previous, seed=seed, executor=executor)
    if (context.quick, context.seed) != (quick, seed):
        raise ValueError(
            f"context: quick={context.quick}, seed={context.seed} must be the report's ({quick}, {seed})"
        )
    context.previous = previous
    if executor is not None:
        context.executor = executor
    return context


def _computed(ctx, spec):
    """``(data, error, seconds)`` of ``spec.compute(ctx)``: ``error`` the failure record (and
    the section's error line) when it raised, else ``None``."""
    t = time.perf_counter()
    try:
        return spec.compute(ctx), None, time.perf_counter() - t
    except Exception as exc:  # a broken section must not lose the rest of the report
        return None, (f"{type(exc).__name__}: {exc}", _section_failure(spec.id)), time.perf_counter() - t


def _rendered(spec, computed):
    """``(section, failure)``: ``spec`` rendered from ``computed`` (:func:`_computed`), and the
    failure record of its compute or render (``None`` when neither raised)."""
    data, error, seconds = computed
    sec = Section(spec.id, spec.title)
    t = time.perf_counter()
    if error is None:
        try:
            spec.render(sec, data)
        except Exception as exc:  # noqa: BLE001 - as a failed compute
            error = (f"{type(exc).__name__}: {exc}", _section_failure(spec.id))
    if error is not None:
        sec = Section(spec.id, spec.title, error=error[0])
    sec.seconds = seconds + time.perf_counter() - t
    return sec, None if error is None else error[1]


def side_by_side(executor) -> bool:
    """Whether a report on ``executor`` computes its :attr:`~.core.SectionSpec.beside` sections
    at once: only when their tasks run on workers that each run one task at a time (local
    processes, or a cluster of one-thread workers).  In-process there is nothing to overlap;
    on a worker with several task threads the stability sweep, which records warnings
    process-wide, would record other sections' warnings."""
    return getattr(executor, "workers", 1) > 1 and getattr(executor, "one_task_per_process", False)


def _plan(ctx, specs):
    """``(before, beside, after)``: the sections of ``specs`` this process computes before the
    side-by-side ones start, those (:func:`side_by_side`; at least two), and the rest, each in
    the order sections run (by stage, page order within one).  Before: every other section of
    stage 0 but those that time code (:attr:`~.core.SectionSpec.alone`), so that while the
    beside ones run this process only renders, which records no warnings (a check's
    :func:`~scatterbench.validation.numerics.probes.fp_warnings` swaps process-wide state,
    which a side-by-side thread's ``warnings.catch_warnings`` would cross)."""
    order = sorted(specs, key=lambda sp: sp.stage)
    beside = [sp for sp in order if sp.beside] if side_by_side(ctx.executor) else []
    if len(beside) < 2:
        return [], [], order
    before = [sp for sp in order if not sp.beside and sp.stage == 0 and not sp.alone]
    return before, beside, [sp for sp in order if sp not in before and sp not in beside]


@contextlib.contextmanager
def _computing(ctx, beside):
    """``{future: spec}`` of the ``beside`` sections' :func:`_computed`, each on a thread of its
    own (in a copy of this thread's context: the backend and precision settings), their tasks
    then sharing the executor's workers; once all have started, this thread runs their
    preloads (:func:`preload`: ArviZ's import, 1.3-2.2 s) while their tasks run.  A section
    that uses what a preload imports calls it too, and waits for this thread's run
    (``diagnostics.load`` takes a lock): one thread imports, and the others import nothing
    meanwhile (ad hoc, 2026-12-08: in ``report --quick`` and the full report, a
    ``sys.meta_path`` hook saw no module imported by a section's thread, and a wrapped
    ``catch_warnings.__enter__`` no swap of the warnings' state but the PTFE section's, after
    its tasks).  Before, a report ran the preloads before any section: on a 16-core machine, on
    its longest path (``benchmarks/report_schedule.py``).  The block's end waits for them."""
    if not beside:
        yield {}
        return
    with ThreadPoolExecutor(len(beside), thread_name_prefix="scatterbench-section") as pool:
        futures = {pool.submit(contextvars.copy_context().run, _computed, ctx, sp): sp for sp in beside}
        preload(beside)
        yield futures


class _Rendering:
    """The sections rendered so far, on this thread (matplotlib's figures are not
    thread-safe), in whatever order they are done; what the later stages read of them (their
    seconds, the failures) is published in the order sections run, as if one by one."""

    def __init__(self, ctx, order, bar):
        self.order, self.bar = order, bar
        self.done, self.failed = {}, {}
        self.times = ctx.cache.setdefault("section_times", {})
        self.failures = ctx.cache.setdefault("section_failures", [])
        self.prior = len(self.failures)  # a shared context's, kept first

    def __call__(self, spec, computed):
        self.done[spec.id], failure = _rendered(spec, computed)
        if failure is not None:
            self.failed[spec.id] = failure
        self.bar.update(1)

    def publish(self):
        ran = [sp.id for sp in self.order if sp.id in self.done]
        self.times.update((sid, self.done[sid].seconds) for sid in ran)
        self.failures[self.prior :] = [self.failed[sid] for sid in ran if sid in self.failed]


def _run_sections(ctx, specs):
    """Every section of ``specs``, as :func:`_plan` orders them: the first ones computed here
    one at a time; the side-by-side ones, while this thread renders the first ones and then
    each of them as it is done; the rest one at a time.  Returns the sections in page order
    and the seconds of two phases: ``beside``, what more workers can shorten, and ``in turn``,
    before and after it, what they cannot (on 2 cores, warm: the full report's 18.9-20.3 s
    one at a time became 10.5-10.6 s, ``report --quick``'s 16.2-18.0 s 8.3-9.1 s, the digests
    unchanged: docs/guide/scaling.md)."""
    before, beside, after = _plan(ctx, specs)
    with _progress(len(specs), "report") as bar:
        render = _Rendering(ctx, sorted(specs, key=lambda sp: sp.stage), bar)
        late = compile_later(ctx.executor, specs)  # while the workers are idle, before the beside ones
        t = time.perf_counter()
        first = [(spec, _computed_after(ctx, spec, late, bar)) for spec in before]
        t_beside = time.perf_counter()
        with _computing(ctx, beside) as futures:
            for spec, computed in first:
                render(spec, computed)
            for fut in as_completed(futures):
                render(futures[fut], fut.result())
        t_after = time.perf_counter()
        for spec in after:
            render.publish()  # provenance shows the seconds, the summary the failures
            render(spec, _computed_after(ctx, spec, late, bar))
        render.publish()
    in_turn = t_beside - t + time.perf_counter() - t_after
    return [render.done[spec.id] for spec in specs], {"beside": t_after - t_beside, "in turn": in_turn}


def _computed_after(ctx, spec, late, bar):
    """:func:`_computed` of ``spec`` once ``late`` (:func:`compile_later`) is done if it
    compiles ``spec``'s loops (then they load from the cache; a failed compile leaves it to
    compile them)."""
    bar.set_postfix_str(spec.id)
    if spec.compiles and late is not None:
        wait_for([late])
    return _computed(ctx, spec)


#: the loops a report runs, as tasks of :func:`compile_ahead`: ``(kernel, precision, option
#: sets, scalar)``, the option sets of the vector loops its models take (recorded from a ``report
#: --quick`` by wrapping ``kernels.vector.lanes_of``: all 6 of Cook-Torrance's, 3 of
#: Maxwell-Beard's 6; None: every one, or a module's entries), whether it calls the scalar loop
#: (recorded by wrapping ``kernels.Compiled.scalar``: only for the options without lanes, the
#: facets' other slopes and FacetBTDF), the Monte Carlo,
#: aperture and disc entries, RoughSubsurfaceBRDF's (the conservation section's reciprocity
#: check takes every registered model: left out, both workers compiled them during the sections,
#: 2 x 4.7 s of CPU), the fused Mueller likelihood of the PTFE section and the small
#: calls' angle check (the main process compiled those two, ~3 s, during the sections).  The
#: loops only a later section runs are that section's (:attr:`~.core.SectionSpec.compiles`: the
#: float32 facet, the speed section's), compiled while the sections before it run
#: (:func:`compile_later`).  A loop missing from both still compiles, on first use.
#:
#: Grouped by process: a process compiles the helpers its loops inline (the kernel's function
#: and everything it calls: numba does not cache them, :mod:`scatterbench.models.kernels`) once
#: for all its loops, so that the loops of one kernel, and the kernels that share helpers
#: (Maxwell-Beard's and FacetBTDF's facets are the facet kernel's), go to one process.  Each
#: in a fresh process with an empty cache (an ad hoc script calling :func:`warm_task`,
#: 2026-11-30, at 8806382): Cook-Torrance's loops as two tasks took 10.6 + 10.1 s of CPU and as
#: one 13.3 s, the facet's 11.1 + 9.3 s and 15.0 s, Maxwell-Beard's 13.3 s alone and 9.6 s after
#: the facet's.  Largest first (``python benchmarks/scaling.py --threads 1 --studies --compile``
#: times each group), so that the processes of a 2-core machine finish together.
_FACET = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (1, 1, 0), (2, 1, 0)]  # three slopes; Smith's lanes of two
COMPILE_GROUPS = (
    (("cook", "float64", None, False), ("montecarlo", "float64", None, False),
     ("single", "float64", [(0, 0, 0), (1, 0, 0)], False), ("diffuse", "float64", [(0, 0, 0)], False)),
    (("facet", "float64", _FACET, True), ("maxwell", "float64", [(0, 0, 1), (1, 0, 0), (1, 0, 1)], False),
     ("btdf", "float64", [], True)),
    (("aperture", "float64", None, False), ("rough", "float64", None, False)),
    (("likelihood", None, None, False),), (("disc", "float64", None, False),),
    (("angles", "float64", None, False),),
)  # fmt: skip


def warm_task(task):
    """Compile (or load) what compile-ahead task ``task`` (of a group of :data:`COMPILE_GROUPS`) names: a
    kernel's loops (:func:`scatterbench.models.kernels.warm`) or the fused likelihoods
    (``"likelihood"``: :func:`scatterbench.validation.fitting.mueller_kernel.warm`, the Mueller
    data's, and :func:`scatterbench.validation.fitting.polarized_kernel.warm`, the polarized
    BRDF's)."""
    if task[0] == "likelihood":  # validation's, not a model kernel
        from scatterbench.validation.fitting import mueller_kernel, polarized_kernel  # numba (heavy): on use

        polarized_kernel.warm()
        return mueller_kernel.warm()
    from scatterbench.models import kernels

    return kernels.warm(*task)


def cold_task(task) -> bool:
    """Whether what ``task`` names (:func:`warm_task`) is not in numba's cache yet."""
    if task[0] == "likelihood":
        from scatterbench.validation.fitting import mueller_kernel, polarized_kernel

        return mueller_kernel.cold() or polarized_kernel.cold()
    from scatterbench.models import kernels

    return kernels.cold(*task)


def warm_group(group):
    """Compile (or load) the tasks of ``group`` (one of :data:`COMPILE_GROUPS`) in turn, in this
    process; returns their kernels' names."""
    return [warm_task(task) for task in group]


def compile_ahead(executor):
    """Start compiling the loops a report runs that numba's cache lacks on ``executor``'s local
    worker processes, a different group of them (:data:`COMPILE_GROUPS`) on each at once, before
    the sections need them: otherwise every process compiled each loop it reached, the workers
    the same ones at the same time.  Returns the future of that (its result raises what a
    compile raised), or ``None``: nothing to compile, one process, a Dask cluster."""
    return _in_background(executor, _cold_groups(executor, COMPILE_GROUPS))


def compile_later(executor, specs):
    """Start compiling, on ``executor``'s local worker processes, the loops that only sections
    computed in this process use (their :attr:`~.core.SectionSpec.compiles`); returns the
    future of that, or ``None`` when nothing is to compile.  A report starts it with its
    sections: while this process computes those before the beside ones, one core at a time,
    the workers are idle; ahead of all sections those loops took every core's time (the float32
    facet: 3.6 s of CPU, ``benchmarks/scaling.py --compile``).  A section with such loops waits
    for the future, so that it loads them rather than compiling them again."""
    return _in_background(
        executor, _cold_groups(executor, [spec.compiles for spec in specs if spec.compiles])
    )


def _in_background(executor, groups):
    """The future of ``executor.map(warm_group, groups)``, run from a thread of its own so that
    this one goes on; ``None`` when ``groups`` is empty."""
    if not groups:
        return None
    pool = ThreadPoolExecutor(1, thread_name_prefix="scatterbench-compile")
    try:
        return pool.submit(executor.map, warm_group, groups, tasks=len(groups))
    finally:
        pool.shutdown(wait=False)  # the thread ends with its one task


def preload(specs):
    """Run, on this thread (a report's main thread), what the sections of ``specs`` need imported
    (:attr:`~.core.SectionSpec.preloads`, each once), once their threads have started
    (:func:`_computing`; a first run, while its workers compile): an import on a section's thread
    beside other sections' imports can cross theirs (877275d: CPython handed one a
    half-imported ``dask.array`` in about one ``report --quick`` of five).  A preload that
    raises is left to the sections that import what it imports, which then fail alone (with
    its error), as a broken section must not lose the rest of the report."""
    for load in dict.fromkeys(fn for spec in specs for fn in spec.preloads):
        with contextlib.suppress(Exception):
            load()


def every_compile_group() -> tuple:
    """The groups a report compiles: :data:`COMPILE_GROUPS` ahead of its sections, then the
    sections' own (:func:`compile_later`)."""
    return COMPILE_GROUPS + tuple(spec.compiles for spec in SECTIONS if spec.compiles)


def _cold_groups(executor, groups) -> list:
    """The groups of ``groups`` with a task not in numba's cache (said on the progress line),
    on local worker processes; none elsewhere (one process, a Dask cluster: each loop
    compiles on first use)."""
    if getattr(executor, "kind", None) != "processes":
        return []
    todo = [group for group in groups if any(cold_task(task) for task in group)]
    if todo:
        from scatterbench.models import kernels

        names = [task[0] for group in todo for task in group]
        kernels.announce(list(dict.fromkeys(names)), f"on {executor.workers} processes")
    return todo


def build_report(
    quick=False,
    previous=None,
    seed=SEED,
    only=None,
    extra_scenes=(),
    checks=None,
    context=None,
    executor=None,
):
    """Run every section; returns ``(results, html)``.  A section that raises is kept
    on the page with its error and counts as a failed check; the others still run.

    ``only``: ids of the sections to compute (summary and provenance always run);
    ``extra_scenes``: scene files shown beside the built-in examples;
    ``checks``: ids of the registered checks the summary judges (default: every one,
    less the slow ones in a quick run: the set ``validate`` judges);
    ``context``: a :class:`~scatterbench.validation.report.core.Context` to run in (its memo shared,
    e.g. with ``validate``); default a new one;
    ``executor``: where the studies run (:mod:`scatterbench.validation.fitting.executors`; default
    the context's, else in-process); the results are the same on any executor.
    """
    ctx = _context(context, quick, previous, seed, executor)
    ctx.cache["extra_scenes"] = list(extra_scenes)
    if checks is not None:
        ctx.cache["check_specs"] = select(checks)
    t0 = time.perf_counter()  # a first run's compilation counts in the report's time
    wanted = None if only is None else set(only) | {"summary", "provenance"}
    specs = [sp for sp in SECTIONS if wanted is None or sp.id in wanted]
    compiling = compile_ahead(ctx.executor)
    if compiling is not None:  # a first run: the preloads while the workers compile (then done)
        preload(specs)
        compiling.result()
    start = time.perf_counter() - t0
    sections, phases = _run_sections(ctx, specs)
    # every check is counted even if the summary section itself failed to draw them
    checks = report_checks(ctx) + ctx.cache["section_failures"]
    summary = tally(checks)
    meta = {
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "git_commit": git_commit(),
        "quick": quick,
        "seed": seed,
        "seconds": time.perf_counter() - t0,
        # where those seconds went: before the sections (compile-ahead), then _run_sections'
        "phase_seconds": {"start": start, **phases},
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


#: the files a report folder holds; an old folder holding anything else is refused
#: rather than deleted by the swap
REPORT_FILES = frozenset({"report.html", "results.json"})


def write_files(folder, results, html):
    """Write ``results.json`` and ``report.html`` into the (new, unpublished) ``folder``."""
    atomic_write_json(os.path.join(folder, "results.json"), results)
    atomic_write_text(os.path.join(folder, "report.html"), html)


def write_report(out_dir, quick=False, previous=None, wait=0.0, **kwargs):
    """Write ``report.html`` and ``results.json`` into ``out_dir``, together: the folder is
    built beside the old one and swapped in whole, under its lock
    (:func:`~scatterbench.validation.atomic.replacing_folder`), so a failed run leaves the
    old pair as it was and a concurrent run on the same folder is refused
    (:class:`~scatterbench.validation.atomic.FolderBusy`).

    The previous ``results.json`` of that folder (if any) is the comparison base
    for "change since previous" unless ``previous`` is given; one that cannot be
    used is said so in ``results["meta"]["previous_problem"]``.
    """
    with replacing_folder(out_dir, REPORT_FILES.__contains__, wait=wait) as build:
        problem = None
        if previous is None:
            previous, problem = read_results_checked(os.path.join(out_dir, "results.json"))
        results, html = build_report(quick=quick, previous=previous, **kwargs)
        if problem:
            results["meta"]["previous_problem"] = problem
        write_files(build, results, html)
    return results
