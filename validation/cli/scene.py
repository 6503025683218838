"""``scatterbench scene``: evaluate a scene file (in-plane and out-of-plane scans)."""

from __future__ import annotations

from scatterbench.models import scene as scene_mod
from scatterbench.validation.studies.scenes import write_scene_outputs

from .args import positive_float, writable_folder

__all__ = ["register"]


def _cmd_scene(args) -> int:

    writable_folder(args.out, "--out")
    sc = scene_mod.load(args.file)
    print(sc.describe())
    if args.tol is None:
        csv_path, png_path = write_scene_outputs(sc, args.out)
    else:
        csv_path, png_path, notes = write_scene_outputs(sc, args.out, tol=args.tol)
        for n in notes:
            print(f"  --tol: {n}")
    print(f"wrote {csv_path} and {png_path}")
    return 0


def register(sub):
    p = sub.add_parser("scene", help="evaluate a scene file: in-plane and out-of-plane scans (CSV + PNG)")
    p.add_argument("file", help="scene TOML file")
    p.add_argument("--out", default="reports/scenes", help="output folder")
    p.add_argument(
        "--tol",
        type=positive_float,
        default=None,
        help="(> 0) pick grid, Monte Carlo pairs and point-source resolution from the measured curves",
    )
    p.set_defaults(func=_cmd_scene)
