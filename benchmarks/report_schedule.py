"""A report's schedule, recorded here and replayed on more workers: an estimate of the report's
time on a machine with more cores, from one run on this one.

    python benchmarks/report_schedule.py [--quick] [--workers 2] [--replay 2 16] [--slower 1.21]
                                         [--save FILE] [--load FILE]

Runs the report (``build_report``, not written) on ``--workers`` local processes and records

* every map a section makes: from which of the report's threads, when, and each task's CPU
  seconds on its worker (``time.thread_time``);
* every section's compute (its thread, start and end) and render (on the report's thread);
* the report's seconds before the sections (``meta.phase_seconds["start"]``).

Then replays that record on ``N`` workers for each ``--replay N``: a task takes its CPU seconds
(times ``--slower`` where ``N`` is more than the workers that ran: a core is slower when every
core of its machine is busy; 1.21 was measured on the 16-core device machine with all 16 busy,
docs/guide/scaling.md), the tasks run first submitted first (``ProcessPoolExecutor``'s queue)
on the first free worker, a section's thread waits for its maps' tasks, and the report's own
work between them takes the wall seconds it took here (including what this machine's two
cores lost to the workers: pessimistic for more cores); the sections computed one at a time,
the renders (the side-by-side ones' as they finish) and the seconds before the sections as
recorded.  What it leaves out: the report's threads sharing one interpreter lock (its threads'
work between maps, a few seconds of a full report, is taken as if each had a core), the cost
of shipping a task (~1 ms), and how more workers change a task's cost other than by
``--slower`` (memory bandwidth; the kernels' threads, a worker's share of the cores).

The replay on ``--workers`` itself is the model's check: it should come out near the measured
seconds, which are printed beside it.  The 16-core figure is an estimate, not a measurement:
``benchmarks/scaling_16core.sh`` measures it where a 16-core machine is lent.
"""

from __future__ import annotations

import argparse
import collections
import heapq
import json
import os
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Timed:
    """``fn`` as a task that also returns its CPU seconds (the mapped function while recording;
    pickled to the workers, which import this script as their main module)."""

    def __init__(self, fn):
        self.fn = fn

    def __call__(self, item):
        cpu = time.thread_time()
        out = self.fn(item)
        return out, time.thread_time() - cpu


class Recorder:
    """Events ``(thread, kind, key, seconds since start, extra)`` of a report's run: ``map``
    (key: the map's number, extra: its tasks' CPU seconds) at its submission, ``wait`` once its
    results are back, ``start`` and ``end`` of a section's compute (key: its id) and
    ``render`` (extra: its seconds)."""

    def __init__(self):
        self.events, self.lock, self.t0 = [], threading.Lock(), time.perf_counter()
        self.wrapped, self.maps = {}, 0

    def log(self, kind, key, extra=None):
        with self.lock:
            name = threading.current_thread().name
            self.events.append((name, kind, key, time.perf_counter() - self.t0, extra))

    def timed(self, fn):
        """One :class:`Timed` per function, so the executor pickles each function once."""
        w = self.wrapped.get(id(fn))
        if w is None or w.fn is not fn:
            w = self.wrapped[id(fn)] = Timed(fn)
        return w

    def install(self, executors, build):
        """Wrap ``ProcessExecutor.map`` and the report's compute and render to log them."""
        submit, computed, rendered = executors.ProcessExecutor.map, build._computed, build._rendered

        def map_(ex, fn, items, tasks=None, meanwhile=None):
            with self.lock:
                self.maps += 1
                key = self.maps
            self.log("map", key)
            out = submit(ex, self.timed(fn), list(items), tasks, meanwhile)
            self.log("wait", key, [cpu for _, cpu in out])
            return [y for y, _ in out]

        def computed_(ctx, spec):
            self.log("start", spec.id)
            try:
                return computed(ctx, spec)
            finally:
                self.log("end", spec.id)

        def rendered_(spec, done):
            t = time.perf_counter()
            out = rendered(spec, done)
            self.log("render", spec.id, time.perf_counter() - t)
            return out

        executors.ProcessExecutor.map, build._computed, build._rendered = map_, computed_, rendered_


def record(quick, workers):
    """Run the report on ``workers`` local processes; returns its record (JSON-ready)."""
    from scatterbench.validation.fitting import executors
    from scatterbench.validation.report import build
    from scatterbench.validation.report.timing import results_digest

    rec = Recorder()
    rec.install(executors, build)
    ex = executors.ProcessExecutor(workers)
    try:
        results, _ = build.build_report(quick=quick, executor=ex)
    finally:
        ex.close()
    meta = results["meta"]
    return {"workers": workers, "quick": quick, "seconds": meta["seconds"], "digest": results_digest(results),
            "phase_seconds": meta["phase_seconds"], "events": rec.events}  # fmt: skip


def programs(events):
    """``(sections, renders, threads)``: per section id, its steps in order (``("work", s)``:
    its thread's own seconds; ``("map", key, [cpu...])``; ``("wait", key)``), its render's
    seconds, the thread that computed it."""
    cpu = {key: extra for _, kind, key, _, extra in events if kind == "wait"}
    sections, renders, threads, current = {}, {}, {}, {}
    for thread, kind, key, t, extra in events:
        if kind == "render":
            renders[key] = extra
        elif kind == "start":
            sections[key], threads[key], current[thread] = [], thread, (key, t)
        elif thread in current:
            sid, last = current[thread]
            steps = sections[sid]
            if kind == "map":
                steps += [("work", t - last), ("map", key, cpu[key])]
            elif kind == "wait":
                steps.append(("wait", key))
            else:  # end
                steps.append(("work", t - last))
                del current[thread]
                continue
            current[thread] = (sid, t)
    return sections, renders, threads


def replay(sections, ids, workers, slower, t):
    """The end time of each section of ``ids``, all started at ``t`` on threads of their own
    and sharing ``workers`` one-task workers (first submitted, first run)."""
    free = [t] * workers
    pc, ready, finish, ends = dict.fromkeys(ids, 0), dict.fromkeys(ids, t), collections.defaultdict(float), {}
    while pc:
        sid = min(pc, key=lambda k: ready[k])  # the thread whose next step comes first
        steps = sections[sid]
        if pc[sid] == len(steps):
            ends[sid] = ready[sid]
            del pc[sid]
            continue
        step = steps[pc[sid]]
        if step[0] == "work":
            ready[sid] += step[1]
        elif step[0] == "map":
            for cpu in step[2]:
                start = max(heapq.heappop(free), ready[sid])
                heapq.heappush(free, start + cpu * slower)
                finish[step[1]] = max(finish[step[1]], start + cpu * slower)
        else:  # wait
            ready[sid] = max(ready[sid], finish[step[1]])
        pc[sid] += 1
    return ends


def phases(rec):
    """``(sections, renders, before, beside, after, lead)``: the record's programs, its section
    ids in three groups (computed on the report's thread before the side-by-side ones started,
    on threads of their own, on the report's thread after them; each in the order they ran),
    and the seconds from the first side-by-side section's start to the report's first render
    (its thread's own work meanwhile: starting the sections, the preloads)."""
    sections, renders, threads = programs(rec["events"])
    starts = {key: t for _, kind, key, t, _ in rec["events"] if kind == "start"}
    order = sorted(sections, key=starts.get)
    beside = [s for s in order if threads[s] != "MainThread"]
    first = min((starts[s] for s in beside), default=float("inf"))
    before = [s for s in order if s not in beside and starts[s] < first]
    after = [s for s in order if s not in beside and s not in before]
    for sid in beside:  # started later than the first (after the preloads): that long later
        sections[sid] = [("work", starts[sid] - first), *sections[sid]]
    drawn = [t - x for _, kind, key, t, x in rec["events"] if kind == "render" and key in before + beside]
    lead = min(drawn) - first if beside and drawn else 0.0
    return sections, renders, before, beside, after, max(lead, 0.0)


def estimate(rec, workers, slower):
    """``(seconds, ends)``: the replayed report on ``workers`` workers and when each of its side-by-side
    sections ended (from the start of the sections)."""
    sections, renders, before, beside, after, lead = phases(rec)
    t = rec["phase_seconds"]["start"]
    for sid in before:
        t = replay(sections, [sid], workers, slower, t)[sid]
    # this thread renders once it has started the side-by-side sections and run the preloads
    # (``lead``), the first sections' renders first
    t_beside, rendered = t, t + lead + sum(renders.get(s, 0.0) for s in before)
    ends = replay(sections, beside, workers, slower, t) if beside else {}
    for sid in sorted(beside, key=ends.get):  # the report's thread renders each as it finishes
        rendered = max(rendered, ends[sid]) + renders.get(sid, 0.0)
    t = rendered
    for sid in after:
        t = replay(sections, [sid], workers, slower, t)[sid] + renders.get(sid, 0.0)
    return t, {s: e - t_beside for s, e in ends.items()}


def report(rec, replays, slower):
    """Print the record's measured seconds and each replay (computing separate from printing:
    :func:`estimate` gives the numbers)."""
    n = rec["workers"]
    print(f"recorded: {'report --quick' if rec['quick'] else 'full report'} on {n} workers, "
          f"{rec['seconds']:.1f} s measured ({', '.join(f'{k} {v:.1f}' for k, v in rec['phase_seconds'].items())}), "
          f"results digest {rec.get('digest')}")  # fmt: skip
    base = None
    for w in replays:
        factor = slower if w > n else 1.0
        total, ends = estimate(rec, w, factor)
        base = total if w == n else base
        last = max(ends, key=ends.get) if ends else "-"
        print(f"replayed on {w:3d} workers, tasks x{factor:g}: {total:6.1f} s; side-by-side sections end "
              + ", ".join(f"{s} {e:.1f}" for s, e in sorted(ends.items(), key=lambda kv: kv[1]))
              + f" s (last: {last})")  # fmt: skip
        if w != n:
            ratio = f", {base / total:.2f}x the replay on {n}" if base else ""
            print(f"  estimate: {rec['seconds'] / total:.2f}x the measured {rec['seconds']:.1f} s{ratio}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="report --quick (default: the full report)")
    ap.add_argument(
        "--workers", type=int, default=2, help="local processes the recorded run uses (default 2)"
    )
    ap.add_argument(
        "--replay", type=int, nargs="+", default=[2, 16], help="workers to replay on (default 2 16)"
    )
    ap.add_argument("--slower", type=float, default=1.21,
                    help="a task's CPU seconds times this on more workers than recorded (default 1.21)")  # fmt: skip
    ap.add_argument("--save", help="write the record here (JSON)")
    ap.add_argument("--load", help="replay this record (JSON from --save) instead of running a report")
    args = ap.parse_args(argv)
    if args.load:
        with open(args.load, encoding="utf-8") as fh:
            rec = json.load(fh)
    else:
        rec = record(args.quick, args.workers)
        if args.save:
            with open(args.save, "w", encoding="utf-8") as fh:
                json.dump(rec, fh)
    report(rec, args.replay, args.slower)


if __name__ == "__main__":
    sys.exit(main())
