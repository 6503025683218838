"""The sampler's settings, stated once: :class:`ChainSettings`.

A fit, a recovery study's members, a model comparison, the command line and
the report all run chains with the same handful of settings; they pass one
frozen, validated object instead of re-listing them.  The command line builds
it from its flags in one place (``_chain_settings`` in :mod:`scatterbench.validation.cli.fit`).
"""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass

import numpy as np

from scatterbench.models.params import check_real

__all__ = ["ChainSettings", "MOVES"]

#: the ensemble moves a chain can use (:attr:`ChainSettings.moves`): emcee's affine-invariant
#: stretch move, or its differential-evolution moves mixed as emcee's documentation suggests
#: for correlated posteriors (DE 80%, DE snooker 20%)
MOVES = ("stretch", "de")


def _integer(name, value, low):
    """``value`` as an ``int >= low`` (the settings' fields, a study's injections, a process
    executor's workers).  Not :func:`scatterbench.models.params.check_real`: that converts to a float,
    which an integer above sys.float_info.max overflows (a valid seed here)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral) or value < low:
        raise ValueError(f"{name} must be an integer >= {low}; got {value!r}")
    return int(value)


def _positive(name, value):
    """``value`` as a finite float > 0, judged by :func:`scatterbench.models.params.check_real` (a bool is
    not a number), with the settings' own message; a complex is refused here, where
    ``check_real`` would take one of no imaginary part."""
    try:
        if isinstance(value, numbers.Real):
            return check_real(name, value, low=0.0, low_open=True)
    except ValueError:
        pass
    raise ValueError(f"{name} must be a finite number > 0; got {value!r}")


@dataclass(frozen=True)
class ChainSettings:
    """Settings of an emcee run: ensemble, seed, stopping rule, optimizer starts.

    Every field is checked on construction; a bad one raises ``ValueError``
    naming the field and its allowed range.

    Parameters
    ----------
    walkers : int
        Ensemble size: even (emcee's stretch move updates it in two halves)
        and >= 2; a fit also needs >= 2 x its free parameters
        (:meth:`require_walkers`).
    seed : int
        >= 0.  Walker initialization, the stretch move and the optimizer's
        starts all derive from it.
    max_steps : int
        Step budget, >= 1.
    check_every : int
        Steps between autocorrelation checks and checkpoints, >= 1.
    tau_factor : float
        Stop when ``N >= tau_factor * max(tau)`` (finite, > 0) ...
    tau_rtol : float
        ... and ``max(tau)`` moved by less than this fraction since the
        previous check (finite, > 0).
    starts : int
        Least-squares starts for the optimum, >= 1.
    burn : int
        Steps run from the starting ball and discarded before the kept chain, >= 0 (emcee's
        burn-in): the kept chain starts from the ensemble and random state they end in, so
        its autocorrelation estimate, and with it the ``N >= tau_factor * tau`` rule, carries
        no start-up transient (``benchmarks/ptfe_joint_fit.py`` prints the estimate without
        the chain's first tenth and half).  The kept chain is then the burned one's
        continuation, bit for bit; their time is the fit's.
    moves : "stretch" | "de"
        The ensemble's proposal (:data:`MOVES`).  The stretch move is emcee's default; on
        the model comparison's curved, strongly correlated posteriors (seed 003, six
        parameters) the differential-evolution mixture reaches ``N >= 50 tau`` in fewer
        steps (``benchmarks/fit_moves.py`` prints both).
    """

    walkers: int = 32
    seed: int = 0
    max_steps: int = 20000
    check_every: int = 100
    tau_factor: float = 50.0
    tau_rtol: float = 0.05
    starts: int = 4
    moves: str = "stretch"
    burn: int = 0

    def __post_init__(self):
        set_ = object.__setattr__  # frozen: normalize numpy scalars to plain int/float once, here
        walkers = _integer("walkers", self.walkers, 2)
        if walkers % 2:
            raise ValueError(f"walkers must be even and >= 2; got {walkers}")
        set_(self, "walkers", walkers)
        set_(self, "seed", _integer("seed", self.seed, 0))
        set_(self, "max_steps", _integer("max_steps", self.max_steps, 1))
        set_(self, "check_every", _integer("check_every", self.check_every, 1))
        set_(self, "tau_factor", _positive("tau_factor", self.tau_factor))
        set_(self, "tau_rtol", _positive("tau_rtol", self.tau_rtol))
        set_(self, "starts", _integer("starts", self.starts, 1))
        set_(self, "burn", _integer("burn", self.burn, 0))
        if not (isinstance(self.moves, str) and self.moves in MOVES):
            raise ValueError(f"moves must be one of {', '.join(MOVES)}; got {self.moves!r}")

    def require_walkers(self, ndim):
        """Raise ``ValueError`` unless the ensemble has >= 2 walkers per free parameter.

        Parameters
        ----------
        ndim : int
            Number of free parameters.

        Returns
        -------
        ChainSettings
            ``self``, for chaining.
        """
        if self.walkers < 2 * ndim:
            raise ValueError(
                f"walkers must be even and >= 2 x free parameters ({2 * ndim}); got {self.walkers}"
            )
        return self

    def replace(self, **changes) -> ChainSettings:
        """A copy with ``changes`` applied (and validated)."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """The fields by name (``posterior.json``'s ``settings``)."""
        return dataclasses.asdict(self)
