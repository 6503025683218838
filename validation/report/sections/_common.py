"""What several sections share: the Agg backend, in-plane scans, the default model set."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # the report draws without a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from scatterbench import models  # noqa: E402
from scatterbench.models.geometry import signed_inplane  # noqa: E402

__all__ = ["plt", "AL", "signed", "inplane", "default_models", "is_heavy", "finish"]

#: aluminium, seed 000's substrate
AL = 1.37 + 7.62j


def signed(x_deg):
    """Signed in-plane angle (deg) -> (theta_r, phi_r) (:func:`scatterbench.models.geometry.signed_inplane`)."""
    return signed_inplane(np.radians(x_deg))


def inplane(model, theta_i, x_deg, incident="unpolarized"):
    """``model.polarization`` over the signed in-plane angles ``x_deg``."""
    return model.polarization(theta_i, *signed(x_deg), incident=incident)


def default_models():
    """One instance per model class: its defaults, or the stability sweep's
    representative base (the point-source wrapper around Cook-Torrance, the Monte
    Carlo model at 200 pairs)."""
    from scatterbench.validation.studies.edge_sweep import _BASES

    out = []
    for cls in models.Model.registry:
        if cls is models.Sum:
            continue
        try:
            out.append(_BASES[cls.__name__]() if cls.__name__ in _BASES else cls())
        except ValueError:
            continue
    return out


def is_heavy(m):
    """Monte Carlo models and wrappers: hundreds of inner evaluations per geometry."""
    return hasattr(m, "pairs") or isinstance(getattr(m, "model", None), models.Model)


def finish(fig, ax, xlabel, ylabel, legend_size):
    """Label ``ax``, give it a legend and lay ``fig`` out; returns ``fig``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=legend_size)
    fig.tight_layout()
    return fig
