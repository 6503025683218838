"""Nightly runs with history and regression detection.

Layout of the history folder::

    HISTORY/runs/<stamp>/report.html, results.json   one folder per completed run
    HISTORY/latest -> runs/<stamp>                   the last completed run (a symlink)

A run is built in ``HISTORY/.tmp-<stamp>/`` and only renamed into ``runs/``
when complete; then ``latest`` is switched atomically (a new symlink renamed
over the old one).  Killing a run at any point therefore leaves the previous
``latest`` report and every earlier results.json untouched.  The history of
results.json is the ``runs`` folder itself.
"""

from __future__ import annotations

import datetime
import json
import os
import shutil

from .build import read_results, write_report

__all__ = ["nightly", "compare_results"]


def compare_results(old, new):
    """Regressions from ``old`` to ``new``: checks that passed and now fail, tracked
    numbers that moved beyond their tolerance, sections that now fail."""
    if not old:
        return []
    out = []
    prev = {c["name"]: c for c in old.get("checks", [])}
    for c in new.get("checks", []):
        p = prev.get(c["name"])
        if p and p["status"] != "fail" and c["status"] == "fail":
            out.append(
                f"check '{c['name']}' passed before and now fails (measured {c['measured']}, tolerance {c['tolerance']})"
            )
    for sid, sec in new.get("sections", {}).items():
        old_sec = old.get("sections", {}).get(sid, {})
        if sec.get("error") and not old_sec.get("error"):
            out.append(f"section '{sid}' failed: {sec['error']}")
        old_tracked = old_sec.get("tracked", {})
        for key, t in sec.get("tracked", {}).items():
            o = old_tracked.get(key)
            if o is None or o.get("value") is None or t.get("value") is None:
                continue
            tol = max(float(t.get("tol", 0.0)), float(o.get("tol", 0.0)))
            if abs(t["value"] - o["value"]) > tol:
                out.append(f"'{key}' moved from {o['value']:.6g} to {t['value']:.6g} (tolerance {tol:.3g})")
    return out


def _latest_results(history):
    link = os.path.join(history, "latest")
    if os.path.islink(link) or os.path.isdir(link):
        return read_results(os.path.join(link, "results.json"))
    return None


def nightly(history, quick=False, stamp=None, _after_build=None, **kwargs):
    """Run the suite into the history folder; returns ``(exit_code, regressions, run_dir)``."""
    os.makedirs(os.path.join(history, "runs"), exist_ok=True)
    for name in os.listdir(history):  # leftovers of killed runs
        if name.startswith(".tmp-"):
            shutil.rmtree(os.path.join(history, name), ignore_errors=True)
    stamp = stamp or datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H%M%SZ")
    previous = _latest_results(history)
    tmp = os.path.join(history, f".tmp-{stamp}")
    os.makedirs(tmp)
    results = write_report(tmp, quick=quick, previous=previous or {}, **kwargs)
    regressions = compare_results(previous, results)
    results["regressions"] = regressions
    with open(os.path.join(tmp, "results.json"), "w") as fh:
        json.dump(results, fh, indent=2, sort_keys=True)
    if _after_build is not None:
        _after_build(tmp)  # test hook: simulate a kill before the commit point
    final = os.path.join(history, "runs", stamp)
    os.replace(tmp, final)
    link_tmp = os.path.join(history, f".tmp-latest-{stamp}")
    os.symlink(os.path.join("runs", stamp), link_tmp)
    os.replace(link_tmp, os.path.join(history, "latest"))
    failed = any(c["status"] == "fail" for c in results["checks"])
    return (1 if (regressions or failed) else 0), regressions, final
