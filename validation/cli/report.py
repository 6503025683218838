"""``scatterbench report`` and ``scatterbench nightly``."""

from __future__ import annotations

import os

from scatterbench.validation.report import nightly, write_report

from .args import check_executor, executor_args, nonneg_float, open_executor, writable_folder


def _report(args) -> int:

    writable_folder(args.out, "--out")
    check_executor(args)
    with open_executor(args) as ex:  # every study of the report runs there; same results on any
        res = write_report(args.out, quick=args.quick, executor=ex)
    if res["meta"].get("previous_problem"):
        print(f"note: no change since the previous report: {res['meta']['previous_problem']}")
    s = res["summary"]
    print(
        f"wrote {os.path.join(args.out, 'report.html')} and results.json: {s['n_checks']} checks, "
        f"{s['n_pass']} pass, {s['n_finding']} findings, {s['n_fail']} fail in {res['meta']['seconds']:.1f} s"
    )
    return 1 if s["n_fail"] else 0


def _nightly(args) -> int:

    check_executor(args)
    with open_executor(args) as ex:  # every study of the run there; same results on any
        run = nightly(args.history, quick=args.quick, wait=args.wait, executor=ex)
    print(f"nightly run written to {run.run_dir}; latest -> {os.path.relpath(run.run_dir, args.history)}")
    for n in run.notes:
        print(f"HISTORY: {n}")
    for r in run.regressions:
        print(f"REGRESSION: {r}")
    if not run.regressions:
        print("no regression against the previous night")
    return run.code


def register(sub):
    p = sub.add_parser("report", help="compute the full validation report (HTML + results.json)")
    p.add_argument("--out", default="reports/latest", help="output folder")
    p.add_argument("--quick", action="store_true", help="fewer points per section (< 2 min)")
    executor_args(p, all_cores=True)
    p.set_defaults(func=_report)
    p = sub.add_parser(
        "nightly", help="run the report into a dated history folder and compare with the previous night"
    )
    p.add_argument("--history", required=True, help="history folder (runs/, latest)")
    p.add_argument("--quick", action="store_true")
    p.add_argument(
        "--wait",
        type=nonneg_float,
        default=3600.0,
        help="seconds to wait for another nightly run holding the history (default 3600), then exit 2",
    )
    executor_args(p, all_cores=True)
    p.set_defaults(func=_nightly)
