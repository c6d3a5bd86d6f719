"""The network's warp probed: what it fences if each column is scaled about itself.

Usage: python docs/warp_probe.py --warp {centre,column} -- EVAL-ARGS...
e.g.   python docs/warp_probe.py --warp column -- --scenarios vru --method bittc \
           --tau 0.8 1.2146 1.8442 2.8 --frame-stride 3 --out /tmp/column_vru.json

Runs ``bittc eval`` (the torch network, ``--method bittc``; ``--out`` required) with the
network's scale warp replaced for every threshold, and records the warp in the JSON:

- ``centre`` (as trained and shipped): the earlier frame's features scaled about the image
  centre, the focus of expansion of the ego's own motion: what stands still aligns.
- ``column``: scaled vertically about the centre row only, each column left in place. A
  road user on a collision course keeps its bearing, so between the two frames it grows
  where it stands; scaled about the image centre it lies (x - c)(1 - 1/s) px to one side
  of where the warp looks (x its column, c the centre's, s the threshold's scale, in the
  pixels of the map warped). Scaled by columns it aligns, up to its own width, and the
  scenery to the sides does not.

Nothing is trained: the shipped weights read a warp they never saw. Figures in
docs/vru.md ("The warp about the image centre, probed").
"""

from __future__ import annotations

import argparse
import json
import os
import sys

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import bittc_core.model.warp as warp  # noqa: E402
from bittc_core.atomic import write_text_atomic  # noqa: E402
from sim.cli import main as bittc  # noqa: E402

_CENTRE_WARP = warp.scale_warp
column_warp = warp.column_warp


def _option(args: list[str], flag: str) -> str | None:
    """The value of ``flag`` in ``args`` (``--flag V`` or ``--flag=V``), or None."""
    for i, a in enumerate(args):
        if a == flag and i + 1 < len(args):
            return args[i + 1]
        if a.startswith(flag + "="):
            return a.split("=", 1)[1]
    return None


def install(chosen) -> list[str]:
    """Put ``chosen`` in place of the shipped warp in every loaded module that holds it by
    name -> those modules' names."""
    names = []
    for name, module in list(sys.modules.items()):
        if (name == "bittc_core" or name.startswith("bittc_core.")) and getattr(module, "scale_warp", None) in (
            _CENTRE_WARP,
            column_warp,
        ):
            module.scale_warp = chosen
            names.append(name)
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--warp", choices=("centre", "column"), required=True)
    ap.add_argument("eval_args", nargs=argparse.REMAINDER, help="after --: the arguments of bittc eval")
    args = ap.parse_args(argv)
    rest = args.eval_args[1:] if args.eval_args[:1] == ["--"] else args.eval_args
    # only the torch network reads the warp at run time: an exported graph or flow would
    # give the shipped figures under either name
    for flag, allowed in (("--method", "bittc"), ("--backend", "torch")):
        value = _option(rest, flag)
        if value is not None and value != allowed:
            ap.error(f"{flag} {value!r}: the probe replaces the torch network's warp; use {flag} {allowed}")
    if _option(rest, "--method") is None:
        ap.error("--method: give --method bittc")
    out = _option(rest, "--out")
    if out is None:
        ap.error("--out: give the JSON file to write (it records the warp)")
    install(column_warp if args.warp == "column" else _CENTRE_WARP)
    rc = bittc(["eval", *rest])
    if rc:
        return rc
    result = json.loads(open(out).read())
    result["warp"] = args.warp
    write_text_atomic(out, json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
