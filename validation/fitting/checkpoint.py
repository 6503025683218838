"""A resumable chain: emcee's in-memory backend that also saves itself to an ``.npz`` file.

:class:`CheckpointBackend` is an :class:`emcee.backends.Backend`: the sampler
stores every step in it, in memory, as emcee's default backend does.  At the
end of each segment of ``check_every`` steps :func:`scatterbench.validation.fitting.sampling.run_chain`
calls :meth:`CheckpointBackend.end_segment`, which records the
autocorrelation time of the whole chain and writes the file atomically
(:mod:`scatterbench.validation.atomic`): the chain, log posterior, acceptance counts, the
sampler's random state, the run's fingerprint, the tau history and the
sampling time.  :meth:`CheckpointBackend.load` restores all of it, so a resumed
sampler continues with the same random numbers: the chain is the same, bit
for bit, as an uninterrupted one.

Files carry a ``format`` entry (:data:`FORMAT`).  A file in another format
(the checkpoints written before this backend had none), an unreadable or
corrupt one, or one made with other settings is refused with a
:class:`CheckpointError` that names the file.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
import zlib

import emcee
import numpy as np

from scatterbench.validation.atomic import atomic_write_bytes

__all__ = ["CheckpointBackend", "CheckpointError", "FORMAT", "saved_steps"]

FORMAT = "scatterbench-chain/2"

#: what a checkpoint file holds besides ``format`` (the random state is numpy's MT19937 tuple, ``rs_*``)
_ENTRIES = (
    "fingerprint",
    "chain",
    "log_prob",
    "accepted",
    "rs_name",
    "rs_keys",
    "rs_pos",
    "rs_has_gauss",
    "rs_cached",
    "tau_history",
    "seconds",
)


class CheckpointError(ValueError):
    """A checkpoint that cannot be resumed: missing, unreadable, in another format, or
    made with other settings.  The message starts with the file's path."""


class CheckpointBackend(emcee.backends.Backend):
    """emcee's in-memory backend, saved to ``path`` at the end of every segment.

    Parameters
    ----------
    path : str or None
        Where :meth:`end_segment` writes the checkpoint; ``None``: memory only.
    fingerprint : str
        Identifies the data, scene, spec and settings of the run; a checkpoint
        is resumed only with the same one (see :meth:`load`).

    Attributes
    ----------
    tau_history : list of (int, ndarray)
        ``(steps, tau)`` at the end of each segment.
    seconds : float
        Sampling time over every segment, including those of earlier runs.
    """

    def __init__(self, path=None, fingerprint=""):
        super().__init__()
        self.path = path
        self.fingerprint = str(fingerprint)
        self.tau_history = []
        self.seconds = 0.0

    def reset(self, nwalkers, ndim):
        super().reset(nwalkers, ndim)
        self.tau_history = []
        self.seconds = 0.0

    @property
    def evaluations(self) -> int:
        """Log-probability evaluations behind the stored chain: the initial ensemble once,
        then every walker at every step."""
        return self.nwalkers * (self.iteration + 1) if self.initialized and self.iteration else 0

    def tau(self) -> np.ndarray:
        """Integrated autocorrelation time of each parameter over the whole chain
        (emcee's estimator, ``c = 5``); NaN below 10 steps."""
        if self.iteration < 10:
            return np.full(self.ndim, np.nan)
        return self.get_autocorr_time(c=5, tol=0, quiet=True)

    def end_segment(self, seconds):
        """After a segment of ``seconds``: record tau, then save the checkpoint (if ``path``)."""
        self.seconds += seconds
        self.tau_history.append((self.iteration, self.tau()))
        if self.path:
            self.save()

    def save(self):
        """Write the checkpoint to ``path`` atomically (a temporary file, then a rename)."""
        name, keys, pos, has_gauss, cached = self.random_state
        buf = io.BytesIO()
        np.savez(
            buf,
            format=np.array(FORMAT),
            fingerprint=np.array(self.fingerprint),
            chain=self.get_chain(),
            log_prob=self.get_log_prob(),
            accepted=self.accepted,
            rs_name=np.array(name),
            rs_keys=keys,
            rs_pos=np.array(pos),
            rs_has_gauss=np.array(has_gauss),
            rs_cached=np.array(cached),
            tau_history=np.array(json.dumps([[s, [float(x) for x in t]] for s, t in self.tau_history])),
            seconds=np.array(self.seconds),
        )
        atomic_write_bytes(self.path, buf.getvalue())

    @classmethod
    def load(cls, path, fingerprint=None, save_to=None) -> CheckpointBackend:
        """The backend saved in ``path``, ready for an :class:`emcee.EnsembleSampler` to continue.

        Parameters
        ----------
        path : str
            A checkpoint written by :meth:`save`.
        fingerprint : str or None
            Refuse a checkpoint made with another fingerprint (``None``: any).
        save_to : str or None
            Where the continued run saves its checkpoints (default ``path``).

        Raises
        ------
        CheckpointError
            Missing, unreadable or corrupt file, another format, another fingerprint.
        """
        entries = _read(path)
        if fingerprint is not None and entries["fingerprint"] != str(fingerprint):
            raise CheckpointError(
                f"{path}: the checkpoint was made with other data, scene, spec, walkers or seed; "
                "resume with the same settings, or start a new run"
            )
        backend = cls(path if save_to is None else save_to, entries["fingerprint"])
        try:
            backend._restore(entries)
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise CheckpointError(f"{path}: a corrupt checkpoint ({exc}); start a new run") from exc
        return backend

    def _restore(self, e):
        chain, log_prob, accepted = e["chain"], e["log_prob"], e["accepted"]
        steps, nwalkers, ndim = chain.shape
        if steps < 1 or log_prob.shape != (steps, nwalkers) or accepted.shape != (nwalkers,):
            raise ValueError(
                f"inconsistent shapes: chain {chain.shape}, log_prob {log_prob.shape}, accepted {accepted.shape}"
            )
        self.reset(nwalkers, ndim)
        self.chain, self.log_prob = chain.astype(self.dtype), log_prob.astype(self.dtype)
        self.accepted = accepted.astype(self.dtype)
        self.iteration = steps
        rs = (
            str(e["rs_name"]),
            e["rs_keys"],
            int(e["rs_pos"]),
            int(e["rs_has_gauss"]),
            float(e["rs_cached"]),
        )
        np.random.RandomState().set_state(rs)  # refuse a state numpy cannot restore, here
        self.random_state = rs
        self.tau_history = [(int(s), np.array(t, dtype=float)) for s, t in json.loads(str(e["tau_history"]))]
        self.seconds = float(e["seconds"])


def _read(path) -> dict:
    """Every entry of a checkpoint file, checked for the format; ``CheckpointError`` otherwise."""
    if not os.path.exists(path):
        raise CheckpointError(f"{path}: no checkpoint to resume")
    try:
        with np.load(path, allow_pickle=False) as z:
            entries = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise CheckpointError(f"{path}: not a readable checkpoint ({exc}); start a new run") from exc
    fmt = str(entries["format"]) if "format" in entries else None
    if fmt != FORMAT:
        made = "an older scatterbench (no format entry)" if fmt is None else f"format {fmt!r}"
        raise CheckpointError(
            f"{path}: a checkpoint of {made}; this version resumes {FORMAT!r} only: start a new run"
        )
    missing = [k for k in _ENTRIES if k not in entries]
    if missing:
        raise CheckpointError(f"{path}: a corrupt checkpoint (missing {', '.join(missing)}); start a new run")
    entries["fingerprint"] = str(entries["fingerprint"])
    return entries


def saved_steps(path) -> int | None:
    """The number of steps the checkpoint ``path`` holds; ``None`` if it cannot be read
    (for messages only: never raises)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return int(z["chain"].shape[0])
    except Exception:  # noqa: BLE001 - a message must not fail
        return None
