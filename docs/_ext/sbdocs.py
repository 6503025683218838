"""Sphinx helpers for the scatterbench site.

* Every model class page (``models.Model`` subclasses) gets its declared-parameter table,
  generated from :meth:`scatterbench.models.params.Declared.parameters` (so it follows the code), and the
  paper equations and SCATMECH / Mitsuba 3 models it corresponds to: the class's own
  ``correspondence`` (:class:`scatterbench.models.facts.Correspondence`).
* ``.. sb-model-table::`` renders that correspondence for every model as one table.

A model class without a ``correspondence`` is a build warning, so with ``-W`` a new model
cannot reach the site undocumented.
"""

from __future__ import annotations

import os
import tomllib

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

LOG = logging.getLogger(__name__)


def _model_classes():
    from scatterbench import models

    return list(models.Model.registry)


def _param_table(cls):
    rows = ["", ".. list-table:: Declared parameters", "   :header-rows: 1", ""]
    rows += ["   * - name", "     - default", "     - allowed", "     - meaning"]
    for p in cls.parameters():
        default = "(required)" if p.required else f"``{p.default!r}``"
        old = f" (old names: {', '.join(p.aliases)})" if p.aliases else ""
        rows += [
            f"   * - ``{p.name}``",
            f"     - {default}",
            f"     - {p.range_text()}",
            f"     - {p.doc}{old}",
        ]
    return rows


def _append_model_info(app, what, name, obj, options, lines):
    from scatterbench import models

    if what != "class" or obj not in models.Model.registry:
        return  # scatterbench's own model classes only (contributed ones document themselves)
    c = obj.correspondence
    if c is None:
        LOG.warning("%s: the class declares no correspondence (models.facts.Correspondence)", name)
        return
    lines += ["", ".. rubric:: Corresponds to", ""]
    lines += [f"* Paper: {c.paper}", f"* SCATMECH: {c.scatmech}", f"* Mitsuba 3: {c.mitsuba}"]
    lines += _param_table(obj)


class ModelTable(SphinxDirective):
    """All model classes with their paper equations and peer models."""

    def run(self):
        for cls in _model_classes():
            if cls.correspondence is None:
                LOG.warning("model %s declares no correspondence", cls.__name__, location=self.get_location())
        rows = [".. list-table::", "   :header-rows: 1", ""]
        rows += ["   * - model", "     - paper", "     - SCATMECH", "     - Mitsuba 3"]
        for cls in _model_classes():
            c = cls.correspondence
            if c is not None:
                rows += [f"   * - :class:`scatterbench.models.{cls.__name__}`", f"     - {c.paper}"]
                rows += [f"     - {c.scatmech}", f"     - {c.mitsuba}"]
        node = nodes.container()
        self.state.nested_parse(StringList(rows), self.content_offset, node)
        return node.children


def _contracts():
    """The import-linter contracts of ``pyproject.toml`` (beside ``docs/``), by id."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    with open(os.path.join(root, "pyproject.toml"), "rb") as fh:
        config = tomllib.load(fh)["tool"]["importlinter"]
    return {c["id"]: c for c in config["contracts"]}


def layer_figure():
    """Draw the ``layers`` contracts of ``validation`` and ``models`` side by side: one box per
    layer, top to bottom, imports running down (for the architecture page's plot)."""
    import matplotlib.pyplot as plt  # matplotlib (heavy): only the plot directive draws

    contracts = _contracts()
    columns = [
        ("scatterbench.validation", contracts["validation"]),
        ("scatterbench.models", contracts["models"]),
    ]
    fig, axes = plt.subplots(1, 2, figsize=(10, 6.5))
    for ax, (title, contract) in zip(axes, columns, strict=True):
        layers = contract["layers"]
        n = len(layers)
        for k, layer in enumerate(layers):
            y = n - 1 - k
            names = [x.strip() for x in layer.replace("|", ":").split(":")]
            text = "\n".join(", ".join(names[i : i + 3]) for i in range(0, len(names), 3))
            ax.add_patch(plt.Rectangle((0.05, y + 0.12), 0.9, 0.76, fc="#e8eef7", ec="#35587a"))
            ax.text(0.5, y + 0.5, text, ha="center", va="center", fontsize=7.5)
            if k < n - 1:  # down to the next layer's box
                ax.annotate("", xy=(0.5, y - 0.12), xytext=(0.5, y + 0.12), arrowprops={"arrowstyle": "->"})
        ax.set_xlim(0, 1)
        ax.set_ylim(-0.1, n)
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.suptitle("imports run down each column (pyproject.toml [tool.importlinter])", fontsize=9)
    fig.tight_layout()
    return fig


def setup(app):
    app.connect("autodoc-process-docstring", _append_model_info, priority=600)
    app.add_directive("sb-model-table", ModelTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
