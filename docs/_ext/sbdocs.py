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


def setup(app):
    app.connect("autodoc-process-docstring", _append_model_info, priority=600)
    app.add_directive("sb-model-table", ModelTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
