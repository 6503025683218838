"""
A fit: posterior corner plot and predictive bands
=================================================

The emcee posterior of the aluminium-flake scene
(``references/scenes/aluminium_flakes_fit.toml``: sigma, the coating index, n and k
of the flakes and the speckle level free) given a held-out synthetic SCATMECH
measurement (``references/data/scatmech_flake_measurement.csv``, its truth in the
JSON sidecar). The same calls ``scatterbench fit`` makes, with a short chain
(16 walkers, 300 steps): the chain does not reach the N > 50 tau rule, so its
intervals are indicative only; ``scatterbench fit`` runs to convergence.
"""

import matplotlib.pyplot as plt

from scatterbench import references
from scatterbench.models import scene
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fit import corner_figure, predictive, predictive_figure, run_fit
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.settings import ChainSettings

sc = scene.load(references.scene_path("aluminium_flakes_fit.toml"))
data = load_data(references.data_path("scatmech_flake_measurement.csv"))
lik = Likelihood(sc, fitspec_from(sc), data)
fit = run_fit(lik, ChainSettings(walkers=16, seed=0, max_steps=300, check_every=100, starts=2))
sampling = fit.summary["sampling"]
print(f"stop: {sampling['stop_reason']}; converged: {sampling['converged']}")
for key, p in fit.summary["parameters"].items():
    truth = data.meta.get("truth", {}).get(key)
    print(f"{key:20s} median {p['median']:.4g}  68%: [{p['p16']:.4g}, {p['p84']:.4g}]  truth {truth}")

# %%
# The posterior, with the sidecar's true values (blue lines).
fig = corner_figure(fit)

# %%
# Posterior-predictive 95 % bands from 100 posterior draws: the model and
# replicated data with the likelihood's noise, with the data.
fig = predictive_figure(fit, predictive(fit, n_draws=100, seed=0))
plt.show()
