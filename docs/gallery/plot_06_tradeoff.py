"""
The speed/accuracy trade: measured Pareto curves
================================================

For each accuracy knob, :func:`scatterbench.validation.studies.tradeoff.study` evaluates a
quantity at every setting, times it, and measures its error against an
independent reference; :func:`~scatterbench.validation.studies.tradeoff.pareto` keeps the
settings that no other setting beats on both cost and error. Quick settings
(``scatterbench tradeoff --quick``). The seconds depend on the machine that
built this page.
"""

import matplotlib.pyplot as plt

from scatterbench.validation.studies.tradeoff import choose, pareto, study

results = study(quick=True)
fig, axes = plt.subplots(1, len(results), figsize=(4 * len(results), 3.6), squeeze=False)
for ax, r in zip(axes[0], results, strict=True):
    front = pareto(r.points)
    ax.loglog([p.seconds for p in r.points], [max(p.error, 1e-18) for p in r.points], "o", color="0.6")
    ax.loglog([p.seconds for p in front], [max(p.error, 1e-18) for p in front], "o-", label="Pareto front")
    for p in r.points:
        ax.annotate(f"{p.setting:g}", (p.seconds, max(p.error, 1e-18)), fontsize=7)
    ax.set_title(r.knob, fontsize=9)
    ax.set_xlabel("cost (s)")
    ax.legend(fontsize=7)
    pick = choose(r, 1e-4)
    print(f"{r.knob}: reference {r.reference}; cheapest setting with measured error <= 1e-4: {pick}")
axes[0][0].set_ylabel("error vs independent reference")
fig.tight_layout()
plt.show()
