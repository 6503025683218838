"""Report building blocks: sections, blocks, rendering, results.json.

A section is declared by a :class:`SectionSpec`: ``compute(ctx)`` returns a small
frozen dataclass of the numbers it shows (no figures, no HTML), and
``render(section, data)`` draws and tabulates only from it.  Everything a page
shows comes from the section's blocks, and every number in a table block is
also stored in ``results.json`` (``numbers``), so the page and the JSON are
one set of values.  ``tracked`` numbers carry a tolerance: ``nightly`` flags a
regression when one moves by more than it between nights.
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import jinja2

from scatterbench.validation.checks.registry import CheckContext

__all__ = [
    "Section",
    "SectionSpec",
    "Context",
    "figure_block",
    "table_block",
    "store_rows",
    "text_block",
    "checks_block",
    "render_html",
]


@dataclass
class Context(CheckContext):
    """A report run: the checks' context (quick, seed, memo shared by checks and
    sections) plus the previous results.json and the sections' scratch ``cache``."""

    previous: dict | None = None  # the previous results.json, if any
    cache: dict = field(default_factory=dict)


@dataclass
class Section:
    id: str
    title: str
    blocks: list = field(default_factory=list)
    numbers: dict = field(default_factory=dict)
    tracked: dict = field(default_factory=dict)  # key -> {"value": v, "tol": t}
    checks: list = field(default_factory=list)  # check records (registry.check_record)
    seconds: float = 0.0
    error: str | None = None

    def as_json(self):
        return {
            "id": self.id,
            "title": self.title,
            "numbers": self.numbers,
            "tracked": self.tracked,
            "checks": self.checks,
            "seconds": self.seconds,
            "error": self.error,
        }


@dataclass(frozen=True)
class SectionSpec:
    """One section of the page: ``compute(ctx) -> data`` (a frozen dataclass of numbers)
    and ``render(section, data)``, which fills the section's blocks, numbers and tracked
    values from ``data`` alone.

    ``stage``: sections run in increasing stage (page order within one); provenance
    (stage 1) shows the others' run times, the summary (stage 2) their failures.

    ``beside``: the section's work is mostly tasks on the run's executor, it records no
    warnings in this process and times nothing: on worker processes it is computed at once
    with the other such sections (:func:`~.build.side_by_side`), so that the workers always
    have tasks, after the other sections of stage 0 and before the rest (:func:`~.build._plan`);
    meanwhile this process renders the sections done.

    ``alone``: the section times code, which other work would slow: computed after the
    ``beside`` ones, with nothing else running.

    ``compiles``: compile tasks (:data:`~.build.COMPILE_GROUPS`' form) of loops that only this
    section uses, one that is not ``beside``: a first run compiles them on a worker while this
    process computes the sections before it (:func:`~.build.compile_later`), not ahead of all
    sections, when every core is compiling.

    ``preloads``: callables of no arguments that import what the section's compute imports on
    first use (ArviZ, and what xarray imports at its first dataset): a report runs them on its
    main thread once the sections have started, and the section calls them too before it uses
    what they import, waiting for that run (each runs once, one thread at a time:
    :func:`~.build.preload`, :func:`~.build._computing`).
    """

    id: str
    title: str
    compute: Callable
    render: Callable
    stage: int = 0
    beside: bool = False
    compiles: tuple = ()
    preloads: tuple = ()
    alone: bool = False


def _clean(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def figure_block(fig, caption, dpi=90):
    """A matplotlib figure embedded as a PNG data URI (no external file, no fetch)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    plt.close(fig)
    return {
        "type": "figure",
        "src": "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode(),
        "caption": caption,
    }


def store_rows(section, key, columns, rows):
    """Store ``rows`` (their ``columns``, non-finite numbers as None) in ``section.numbers[key]``
    and return them: results.json's list of row dicts, whether or not a table shows it."""
    clean_rows = [{c: _clean(r.get(c)) for c in columns} for r in rows]
    section.numbers[key] = clean_rows
    return clean_rows


def table_block(section, key, columns, rows, caption="", fmt=None):
    """A table whose cells are also stored in ``section.numbers[key]`` (list of row dicts)."""
    fmt = fmt or {}
    clean_rows = store_rows(section, key, columns, rows)
    shown = []
    for r in clean_rows:
        cells = []
        for c in columns:
            v = r[c]
            if v is None:
                cells.append("—")
            elif isinstance(v, float):
                cells.append(format(v, fmt.get(c, ".4g")))
            else:
                cells.append(str(v))
        shown.append(cells)
    return {"type": "table", "key": key, "columns": list(columns), "rows": shown, "caption": caption}


def text_block(text):
    return {"type": "text", "text": text}


def checks_block(checks, previous=None):
    """Checks with measured value, tolerance, status and change since the previous run."""
    prev = {c["name"]: c for c in (previous or [])}
    rows = []
    for c in checks:
        p = prev.get(c["name"])
        if p is None:
            change = "new"
        elif p["status"] != c["status"]:
            change = f"{p['status']} -> {c['status']}"
        else:
            dm = (c["measured"] or 0.0) - (p["measured"] or 0.0)
            change = "unchanged" if dm == 0 else f"{dm:+.3g}"
        rows.append({**c, "change": change})
    return {"type": "checks", "rows": rows}


_ENV = None


def _env():
    global _ENV
    if _ENV is None:
        _ENV = jinja2.Environment(
            loader=jinja2.PackageLoader("scatterbench.validation.report", "templates"),
            autoescape=jinja2.select_autoescape(enabled_extensions=("html", "j2"), default=True),
            undefined=jinja2.StrictUndefined,
        )
        _ENV.filters["g"] = lambda v, spec=".4g": "—" if v is None else format(v, spec)
    return _ENV


def render_html(meta, sections, summary):
    return _env().get_template("report.html.j2").render(meta=meta, sections=sections, summary=summary)
