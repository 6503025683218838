"""Generate the committed thin-film reference values from the ``tmm`` package.

Run once with tmm installed (``pip install tmm``, or ``pip install ".[peers]"``).
Writes ``../data/tmm_reference.csv``: ``tmm.coh_tmm`` amplitude coefficients
``r`` and ``t`` (complex, as real and imaginary columns) for both
polarizations, for random stacks of 1-4 films (transparent and absorbing,
thicknesses 0-500 nm, some of exactly 0), substrates (transparent, absorbing,
and below the incident index for total internal reflection), incident media
1 and 1.5, wavelengths 380-780 nm and angles 0-89 deg (``role`` "random").

Then the stacks of films on a coating crossed both ways (``role`` "down", each followed by its
"up" row; ``tests/test_coating_films.py``): 1-4 films (some absorbing, some of zero
thickness) on a real coating index in [1, 2.5], crossed down from the ambient (``n0 = 1``,
``theta0`` in [0, 89] deg) and up from the coating (``n0`` the coating, the films reversed, on
the ambient 1, ``theta0`` the refracted angle ``asin(sin(theta0_down) / n)``).  These rows also
carry tmm's power transmittances ``T_s``, ``T_p`` (empty in the "random" rows).

tmm's conventions are those of :mod:`scatterbench.models.thin_film` (Born & Wolf): ``r_p``
with ``r_p = -r_s`` at normal incidence, ``t_p`` the ratio of the p components
of the electric fields; ``n + ik`` with ``k >= 0`` absorbing.  The script
stores tmm's numbers as they are; ``tests/test_thin_film.py`` compares.
Layers are written as ``n_re;n_im;d_nm`` triples separated by ``|``.  Usage::

    python references/scripts/make_tmm_reference.py [--cases 400] [--seed 20261216] \
        [--both-ways 300] [--both-ways-seed 7]
"""

from __future__ import annotations

import argparse
import datetime
import math
from importlib import metadata

import numpy as np
import tmm
from _write import write_csv


def _index(rng, low, high, absorbing):
    return complex(rng.uniform(low, high), rng.uniform(0.0, 3.0) if absorbing else 0.0)


def _films(rng):
    """1-4 films ``[(index, d_nm)]``: indices 1.2-3, 30 % absorbing (k up to 3), thicknesses
    0-500 nm, 10 % exactly 0."""
    films = []
    for _ in range(int(rng.integers(1, 5))):
        d = 0.0 if rng.random() < 0.1 else float(rng.uniform(0.0, 500.0))
        films.append((_index(rng, 1.2, 3.0, rng.random() < 0.3), d))
    return films


def random_case(rng):
    """``(n0, films [(index, d_nm)], substrate, wavelength_nm, theta0)``."""
    n0 = float(rng.choice([1.0, 1.5]))
    films = _films(rng)
    kind = rng.random()
    if kind < 0.3:  # metal
        sub = _index(rng, 0.1, 3.0, True)
        sub = complex(sub.real, rng.uniform(1.0, 8.0))
    elif kind < 0.5:  # below the incident index: total internal reflection beyond critical
        sub = complex(rng.uniform(1.0, n0) if n0 > 1 else rng.uniform(1.2, 2.0), 0.0)
    else:
        sub = _index(rng, 1.2, 4.0, rng.random() < 0.3)
    return n0, films, sub, float(rng.uniform(380.0, 780.0)), float(rng.uniform(0.0, math.radians(89.0)))


def coating_case(rng):
    """``(films, coating, wavelength_nm, theta0)``: :func:`_films` on a real coating index
    1-2.5, crossed from the ambient at ``theta0``."""
    films = _films(rng)
    n = float(rng.uniform(1.0, 2.5))
    lam = float(rng.uniform(380.0, 780.0))
    return films, n, lam, float(rng.uniform(0.0, math.radians(89.0)))


def both_ways(case):
    """The "down" and "up" cases of one :func:`coating_case`, as :func:`row` takes them."""
    films, n, lam, th = case
    down = (1.0, films, complex(n), lam, th)
    up = (n, films[::-1], 1.0 + 0j, lam, math.asin(math.sin(th) / n))
    return down, up


def row(case, role="random"):
    n0, films, sub, lam, th = case
    n_list = [n0] + [f[0] for f in films] + [sub]
    d_list = [np.inf] + [f[1] for f in films] + [np.inf]
    out, flux = [], []
    for pol in ("s", "p"):
        res = tmm.coh_tmm(pol, n_list, d_list, th, lam)
        out += [complex(res["r"]), complex(res["t"])]
        flux.append(float(res["T"]) if role != "random" else "")
    layers = "|".join(f"{n.real!r};{n.imag!r};{d!r}" for n, d in films)
    rs, ts, rp, tp = out
    coefficients = [v for z in (rs, rp, ts, tp) for v in (z.real, z.imag)]
    return [n0, layers, sub.real, sub.imag, lam, th] + coefficients + flux + [role]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=400)
    ap.add_argument("--seed", type=int, default=20261216)
    ap.add_argument("--both-ways", type=int, default=300)
    ap.add_argument("--both-ways-seed", type=int, default=7)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = [row(random_case(rng)) for _ in range(args.cases)]
    rng = np.random.default_rng(args.both_ways_seed)
    for _ in range(args.both_ways):
        down, up = both_ways(coating_case(rng))
        rows += [row(down, "down"), row(up, "up")]
    header = ["n0", "layers", "substrate_n", "substrate_k", "wavelength_nm", "theta0"]
    header += [f"{c}_{p}" for c in ("rs", "rp", "ts", "tp") for p in ("re", "im")]
    header += ["T_s", "T_p", "role"]
    write_csv(
        "tmm_reference.csv",
        [
            f"Generated by references/scripts/make_tmm_reference.py on {datetime.date.today()}",
            f"tmm {metadata.version('tmm')} coh_tmm; seed {args.seed} ({args.cases} 'random' rows), "
            f"seed {args.both_ways_seed} ({args.both_ways} 'down' rows, each followed by its 'up' row);",
            "theta0 in radians in the incident medium n0; layers 'n;k;d_nm' from the incident side,",
            "'|'-separated; amplitude coefficients r, t (t_p: ratio of the p electric-field",
            "components); T_s, T_p: tmm's power transmittances (both-ways rows only).",
        ],
        header,
        rows,
    )


if __name__ == "__main__":
    main()
