"""``scatterbench fit`` (the study commands are in :mod:`scatterbench.validation.cli.study`).

Output folders are refused when they exist and are not empty, unless
``--force`` (replace the results) or, for ``fit``, ``--resume`` (continue the
chain saved in ``DIR/chain.npz``, or the one an interrupted or failed run left in
``.DIR.partial/``); every flag and input is checked before the optimizer starts.
The folder is built beside the old one and swapped in whole, under the folder's
lock (``.DIR.lock``): a failed run leaves the previous results intact, and a
second run on the same folder is refused (exit 2) while the first runs.  Ctrl-C
during a fit says how to resume (exit 130).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import time

from scatterbench.models import scene as scene_mod
from scatterbench.validation.atomic import beside, folder_lock, replacing_folder
from scatterbench.validation.fitting.checkpoint import saved_steps
from scatterbench.validation.fitting.datafile import load_data
from scatterbench.validation.fitting.fit import run_fit, write_fit
from scatterbench.validation.fitting.fitspec import fitspec_from
from scatterbench.validation.fitting.likelihood import Likelihood
from scatterbench.validation.fitting.mueller_data import load_mueller_data
from scatterbench.validation.fitting.mueller_fit import is_mueller_file, mueller_likelihood, write_mueller_fit
from scatterbench.validation.fitting.settings import MOVES, ChainSettings

from .args import UsageError, check_executor, executor_args, open_executor, writable_folder

__all__ = ["register"]


def _check_out(out, force, resume=None):
    """Raise :class:`UsageError` unless ``out`` can take the results: a writable folder,
    empty unless ``force`` (or ``resume``: ``None`` where the command has no --resume)."""
    if force and resume:
        raise UsageError(
            "--force and --resume: give one (--force replaces the results, --resume continues them)"
        )
    writable_folder(out, "--out")
    # the folder is replaced whole (renamed): its parent must take the new one and the lock
    writable_folder(os.path.dirname(os.path.abspath(out)), "--out")
    if os.path.isdir(out) and os.listdir(out) and not (force or resume):
        raise UsageError(
            f"{out} exists and is not empty; use --force to overwrite it"
            + (" or --resume" if resume is not None else "")
        )


@contextlib.contextmanager
def locked_out(args, resume=None):
    """Hold ``args.out``'s lock for the block (another run writing it: ``FolderBusy``, exit 2),
    with :func:`_check_out` repeated under it (another run may have filled the folder)."""
    with folder_lock(args.out):
        _check_out(args.out, args.force, resume)
        yield


# one definition of the executor flags (cli/args.py); the study commands import them from here
_check_executor, _open_executor, _executor_args = check_executor, open_executor, executor_args


def _spec_args(p):
    p.add_argument("--scene", required=True, help="scene TOML file (model, starting values, [fit] table)")
    p.add_argument(
        "--free",
        action="append",
        default=None,
        metavar="KEY:LOW:HIGH[:PRIOR]",
        help="free parameter (repeatable; replaces the scene's [fit] free list), e.g. substrate.sigma:0.01:1:log",
    )
    p.add_argument(
        "--noise",
        action="append",
        default=None,
        metavar="TERM=VALUE|TERM:LOW:HIGH[:PRIOR]",
        help="noise term brdf (fractional), eta_deg, P, P_C: fixed value or free range",
    )
    p.add_argument(
        "--near-specular-deg", type=float, default=None, help="mask rows within this angle of specular"
    )
    p.add_argument(
        "--exclude",
        action="append",
        default=None,
        metavar="AXIS=LO:HI[,AXIS=LO:HI]",
        help="mask a box, e.g. theta_r_deg=53:67,phi_r_deg=180:180 (repeatable)",
    )


def _mcmc_args(p, walkers=None, max_steps=None):
    """The sampler flags; defaults: :class:`ChainSettings`' unless ``walkers``/``max_steps`` given."""

    d = ChainSettings()
    p.add_argument("--walkers", type=int, default=walkers or d.walkers)
    p.add_argument("--seed", type=int, default=d.seed)
    p.add_argument("--max-steps", type=int, default=max_steps or d.max_steps, help="step budget")
    p.add_argument(
        "--check-every", type=int, default=d.check_every, help="steps between tau checks and checkpoints"
    )
    p.add_argument("--tau-factor", type=float, default=d.tau_factor, help="stop when steps >= this x tau")
    p.add_argument("--starts", type=int, default=d.starts, help="least-squares starts for the optimum")
    p.add_argument(
        "--moves",
        choices=MOVES,
        default=d.moves,
        help="ensemble proposal: emcee's stretch move, or differential evolution (DE 80%%, snooker 20%%)",
    )
    p.add_argument(
        "--burn",
        type=int,
        default=d.burn,
        help="steps run and discarded before the kept chain (its tau then carries no start-up transient)",
    )


def _load(args):
    """The scene, data, fit spec and likelihood of the command line, every one checked
    (and against each other) before any work."""

    sc = scene_mod.load(args.scene)
    data = load_data(args.data)
    spec = fitspec_from(sc, args.free, args.noise, args.near_specular_deg, args.exclude)
    return sc, data, spec, Likelihood(sc, spec, data)  # refuses a spec the data cannot inform


def _load_and_describe(args):
    """The chain settings from the flags and ``_load``'s inputs, ``(settings, scene, data,
    spec, likelihood)``, with the scene and fit spec printed."""
    settings = _chain_settings(args)
    sc, data, spec, lik = _load(args)
    _require_walkers(settings, len(spec.free))
    if lik.scene is not sc:
        print(
            f"detector: the data's sidecar records aperture_deg = {lik.scene.aperture_deg:g} "
            f"(the scene says {sc.aperture_deg:g}); the fit uses the data's"
        )
    print(lik.scene.describe())
    print(spec.describe())
    return settings, sc, data, spec, lik


def _chain_settings(args):
    """The sampler settings of fit and the studies, built from their flags here and only
    here; a flag out of range is a :class:`UsageError` naming it."""

    try:
        return ChainSettings(
            walkers=args.walkers,
            seed=args.seed,
            max_steps=args.max_steps,
            check_every=args.check_every,
            tau_factor=args.tau_factor,
            starts=args.starts,
            moves=args.moves,
            burn=args.burn,
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from exc


def _require_walkers(settings, ndim):
    try:
        settings.require_walkers(ndim)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc


def _interrupted(ck, final):
    """The one line Ctrl-C prints: where the chain is and how to continue it."""

    saved = ck if os.path.exists(ck) else final if os.path.exists(final) else None
    if saved is None:
        print(
            "interrupted before the first checkpoint: nothing saved; run the command again", file=sys.stderr
        )
    else:
        steps = saved_steps(saved)
        print(
            f"interrupted: the chain{'' if steps is None else f' ({steps} steps)'} is saved in {saved}; "
            "continue it with the same command and --resume (instead of --force)",
            file=sys.stderr,
        )
    return 130


#: the files ``fit`` writes into its folder; an old folder holding anything else is refused
#: rather than deleted by the swap
FIT_FILES = frozenset(
    {"posterior.json", "chain.npz", "chain.partial.npz", "corner.png", "predictive.png", "residuals.png"}
    | {"posterior_samples.npz"}  # a Mueller-data fit's samples (fitting.mueller_fit)
)


def _run_fit(args, lik, settings, write=write_fit):
    """Run (or resume) the chain and write the results with ``write`` (``write_fit``, or
    ``write_mueller_fit`` for Mueller-matrix data); returns the posterior summary, or the
    exit code 130 after Ctrl-C.

    The new folder is built beside ``args.out`` in ``.NAME.partial/`` (its running
    checkpoint is chain.partial.npz there) and swapped in whole when every file is
    written (:func:`~scatterbench.validation.atomic.replacing_folder`): a failed or
    interrupted run leaves the previous results as they were.  The build is kept when
    the run fails, so ``--resume`` continues its chain; the caller holds the folder's lock,
    so no other run shares the checkpoint."""

    build = beside(args.out, "partial")
    if not args.resume:
        shutil.rmtree(build, ignore_errors=True)  # a fresh run: an earlier run's build is not continued
    ck = os.path.join(build, "chain.partial.npz")
    final = os.path.join(args.out, "chain.npz")
    try:
        with replacing_folder(args.out, FIT_FILES.__contains__, build, (BaseException,), lock=False):
            with _open_executor(args) as ex:
                res = run_fit(
                    lik,
                    settings,
                    executor=ex,
                    checkpoint=ck,
                    resume=args.resume,
                    resume_from=ck if os.path.exists(ck) else final,
                    progress=not args.no_progress,
                )
                executor = ex.describe()
            os.replace(ck, os.path.join(build, "chain.npz"))
            kw = {} if write is write_mueller_fit else {"plots": not args.no_plots}
            return write(res, build, data_path=args.data, scene_path=args.scene, executor_desc=executor, **kw)
    except BaseException as exc:
        _keep_checkpoint_only(build, ck)
        if isinstance(exc, KeyboardInterrupt):
            return _interrupted(ck, final)
        raise


def _keep_checkpoint_only(build, ck):
    """After a failed or interrupted run: the build keeps its chain as ``ck`` (for --resume)
    and nothing else (half-written results must not be swapped in by a later run); a build
    without a chain is removed."""
    done = os.path.join(build, "chain.npz")
    if os.path.exists(done) and not os.path.exists(ck):
        os.replace(done, ck)  # the run failed after its chain was complete
    if not os.path.exists(ck):
        shutil.rmtree(build, ignore_errors=True)
        return
    for name in os.listdir(build):
        if name != os.path.basename(ck):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(os.path.join(build, name))


def _chain_problem(post):
    """Why the chain cannot be read as a posterior (``None``: it can): no walker ever moved,
    so its percentiles are the starting ball (its tau is NaN too).  A NaN tau alone is a
    chain too short to estimate it: "NOT converged", said already, not a failure."""
    if not post["sampling"]["acceptance_mean"] > 0:
        return "the chain never moved (acceptance 0): the percentiles are its starting ball, not a posterior"
    return None


def _print_sampling(post, total_seconds):
    s, timing = post["sampling"], post["timing"]
    print(f"\n{s['stop_reason']}")
    print(
        f"walkers {s['walkers']}, steps {s['steps']}, tau (steps) "
        + ", ".join(f"{t:.1f}" for t in s["tau_steps"])
        + f"; acceptance {s['acceptance_mean']:.3f} (min {s['acceptance_min']:.3f}); burn-in {s['burn_in']}, thin {s['thin']}"
    )
    print(
        f"sampling time {timing['sampling_seconds']:.1f} s, {s['log_prob_evaluations']} likelihood "
        f"evaluations, {timing['evaluations_per_second']:.0f} evaluations/s (total {total_seconds:.1f} s)"
    )


def _print_posterior(post):
    print(
        f"\n{'parameter':<22} {'2.5%':>10} {'16%':>10} {'50%':>10} {'84%':>10} {'97.5%':>10}"
        + ("  truth" if "truth_check" in post else "")
    )
    for k, p in post["parameters"].items():
        line = f"{k:<22} {p['p2.5']:>10.5g} {p['p16']:>10.5g} {p['p50']:>10.5g} {p['p84']:>10.5g} {p['p97.5']:>10.5g}"
        tc = post.get("truth_check", {}).get(k)
        if tc:
            line += f"  {tc['true']:g} ({'inside' if tc['inside_95'] else 'OUTSIDE'} 95%, {'inside' if tc['inside_68'] else 'outside'} 68%)"
        print(line)
    pressed = {k: p["at_bound"] for k, p in post["parameters"].items() if p.get("at_bound", 0.0) > 0.1}
    if pressed:  # more than 5x what a flat posterior puts within 1% of its two bounds
        print(
            "posterior pressed against a prior bound (fraction of samples within 1% of the range from it): "
            + ", ".join(f"{k} {v:.2f}" for k, v in pressed.items())
            + "; the model reaches the data only at the bound, or the bound is too narrow"
        )
    ic = post["information_criteria"]
    print(f"max ln L {ic['max_log_likelihood']:.2f}, AIC {ic['AIC']:.2f}, BIC {ic['BIC']:.2f}")
    for t, c in post["posterior_predictive"].items():
        print(
            f"predictive check {t}: {c['inside_68']:.2f} of rows inside 68%, {c['inside_95']:.2f} inside 95%"
        )


def _cmd_fit(args) -> int:
    _check_out(args.out, args.force, args.resume)
    _check_executor(args)
    if is_mueller_file(args.data):
        return _cmd_fit_mueller(args)
    settings, _, data, _, lik = _load_and_describe(args)
    print(
        f"data: {data.path}: {len(data)} rows, {lik.n_points} used; likelihood terms: {', '.join(lik.terms)}"
    )
    t0 = time.perf_counter()
    with locked_out(args, args.resume):  # held from the check of --out to the swap
        post = _run_fit(args, lik, settings)
    if isinstance(post, int):  # interrupted
        return post
    _print_sampling(post, time.perf_counter() - t0)
    _print_posterior(post)
    print(
        f"wrote {args.out}/posterior.json, chain.npz"
        + ("" if args.no_plots else ", corner.png, predictive.png, residuals.png")
    )
    problem = _chain_problem(post)
    if problem:
        print(f"FAILED: {problem}")
        return 1
    return 0


def _cmd_fit_mueller(args) -> int:
    """``fit`` on Mueller-matrix data (NIST's file as published, or scatterbench-mueller/1): the
    scene's ``[fit]`` and ``[fit.mueller]`` tables (fitting.mueller_spec); --free replaces the
    free list, the BRDF-data flags --noise, --near-specular-deg and --exclude do not apply."""
    for flag, given in (
        ("--noise", args.noise),
        ("--near-specular-deg", args.near_specular_deg),
        ("--exclude", args.exclude),
    ):
        if given is not None:
            raise UsageError(f"{flag}: not for Mueller-matrix data; use the scene's [fit.mueller] table")
    settings = _chain_settings(args)
    sc = scene_mod.load(args.scene)
    data = load_mueller_data(args.data)
    lik = mueller_likelihood(sc, data, args.free)
    _require_walkers(settings, len(lik.spec.free))
    print(lik.scene.describe())
    print(lik.spec.describe())
    print(f"data: {data.path}: {len(data)} rows, {len(lik.data)} used, basis {data.basis}")
    t0 = time.perf_counter()
    with locked_out(args, args.resume):  # held from the check of --out to the swap
        post = _run_fit(args, lik, settings, write=write_mueller_fit)
    if isinstance(post, int):  # interrupted
        return post
    _print_sampling(post, time.perf_counter() - t0)
    _print_posterior(post)
    print(f"wrote {args.out}/posterior.json, posterior_samples.npz, chain.npz")
    problem = _chain_problem(post)
    if problem:
        print(f"FAILED: {problem}")
        return 1
    return 0


def register(sub):
    p = sub.add_parser("fit", help="emcee posterior of a scene's free parameters given a data file")
    p.add_argument(
        "data",
        help="data CSV (see validation/datafile.py; JSON sidecar beside it), or Mueller-matrix data "
        "(NIST's PTFE.data.csv as published, or scatterbench-mueller/1: see fitting/mueller_data.py)",
    )
    _spec_args(p)
    p.add_argument(
        "--out", required=True, help="output folder (refused if it exists, unless --force/--resume)"
    )
    _mcmc_args(p)
    _executor_args(p)
    p.add_argument("--force", action="store_true", help="overwrite an existing output folder")
    p.add_argument(
        "--resume", action="store_true", help="continue the chain in OUT/chain.npz (same settings)"
    )
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("--no-plots", action="store_true")
    p.set_defaults(func=_cmd_fit)
