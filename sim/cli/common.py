"""Flag parsing and output-directory checks shared by the subcommands."""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from bittc_core.errors import CliError

MIN_SIDE_PX = 16  # bounds of an image size (``parse_size``) [px]
MAX_SIZE_HW_PX = (2048, 4096)
_SIZE_BOUNDS = (
    f"height must be in [{MIN_SIDE_PX}, {MAX_SIZE_HW_PX[0]}] and width in [{MIN_SIDE_PX}, {MAX_SIZE_HW_PX[1]}] px"
)


def _size_in_bounds(h: int, w: int) -> bool:
    return MIN_SIDE_PX <= h <= MAX_SIZE_HW_PX[0] and MIN_SIDE_PX <= w <= MAX_SIZE_HW_PX[1]


def parse_size(text: str) -> tuple[int, int]:
    """'96x288' -> (96, 288): height x width in px."""
    m = re.fullmatch(r"(\d+)x(\d+)", text.strip().lower())
    if not m:
        raise CliError(f"--size {text!r}: expected HxW in pixels, e.g. 96x288")
    h, w = int(m.group(1)), int(m.group(2))
    if not _size_in_bounds(h, w):
        raise CliError(f"--size {text!r}: {_SIZE_BOUNDS}")
    return h, w


def check_frame_size(size_hw: tuple[int, int], method: str, what: str, hint: str = " (--size HxW resizes)") -> None:
    """Frames the estimator can use: within ``parse_size``'s bounds, and for the network
    multiples of its feature stride (3 px). ``hint`` ends the error message."""
    from bittc_core.model.network import FEATURE_STRIDE

    h, w = size_hw
    if not _size_in_bounds(h, w):
        raise CliError(f"{what}: {h}x{w} px; {_SIZE_BOUNDS}{hint}")
    if method == "bittc" and (h % FEATURE_STRIDE or w % FEATURE_STRIDE):
        raise CliError(
            f"{what}: {h}x{w} px; the network needs height and width in multiples of {FEATURE_STRIDE} px{hint}"
        )


def non_negative_int(name: str, value: int, upper: int | None = None) -> int:
    if value < 0 or (upper is not None and value > upper):
        raise CliError(
            f"{name} {value}: must be in [0, {upper}]" if upper is not None else f"{name} {value}: must be >= 0"
        )
    return value


def texture_style(ground: str, vehicles: str):
    """-> ``sim.textures.TextureStyle``; an unknown style names its flag."""
    from sim.textures import GROUND_STYLES, VEHICLE_STYLES, TextureStyle

    if ground not in GROUND_STYLES:
        raise CliError(f"--ground-texture {ground!r}: must be one of {', '.join(GROUND_STYLES)}")
    if vehicles not in VEHICLE_STYLES:
        raise CliError(f"--vehicle-texture {vehicles!r}: must be one of {', '.join(VEHICLE_STYLES)}")
    return TextureStyle(ground, vehicles)


#: every --seed is an integer in [0, MAX_SEED] (numpy's legacy seeding and torch take it)
MAX_SEED = 2**32 - 1
DEVICES = ("auto", "cpu", "cuda")


def add_seed_flag(parser, what: str, default: int | None = 0) -> None:
    """--seed (``check_seed`` bounds it); ``default`` None: required."""
    tail = "" if default is None else f"; default {default}"
    parser.add_argument(
        "--seed", type=int, default=default, required=default is None, help=f"{what} (0 to 2^32 - 1{tail})"
    )


def check_seed(value: int, flag: str = "--seed") -> int:
    """A seed in [0, MAX_SEED]: the bounds of every subcommand's --seed."""
    return non_negative_int(flag, value, MAX_SEED)


def add_device_flag(parser) -> None:
    parser.add_argument(
        "--device",
        default="auto",
        choices=DEVICES,
        help="where the network runs: auto (cuda when available, default), cpu or cuda",
    )


def check_device(value: str) -> str:
    if value not in DEVICES:
        raise CliError(f"--device {value!r}: expected auto, cpu or cuda")
    return value


def flag_error(err: Exception, flags: dict[str, str]) -> Exception:
    """A library error whose message starts with a field name (``"seed -1: must be >= 0"``,
    ``"seeds: ..."``) -> a ``CliError`` with the same message naming the field's flag
    (``flags[field]``); any other error is returned as it is (``main`` prints it too)."""
    text = str(err)
    for field, flag in flags.items():
        if text.startswith(field) and text[len(field) : len(field) + 1] in ("", " ", ":"):
            return CliError(flag + text[len(field) :])
    return err


def writable_dir(path: str) -> Path:
    """Create ``path`` if needed and prove it writable (nothing is left behind)."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise CliError(f"--out {path!r}: exists and is not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=p, prefix=".probe")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise CliError(f"--out {path!r}: not writable ({e.strerror})") from None
    return p


def output_file(value: str, suffixes: tuple[str, ...], flag: str = "--out") -> Path:
    """The file an ``--out FILE`` flag names, refused unless it ends in one of ``suffixes``
    (the first one named in the message), is not a folder, and its folder exists."""
    out = Path(value)
    if out.suffix not in suffixes or out.is_dir():
        raise CliError(f"{flag} {value!r}: expected a {suffixes[0]} file")
    if not out.parent.is_dir():
        raise CliError(f"{flag} {value!r}: folder {str(out.parent)!r} does not exist")
    return out


BACKENDS = ("torch", "onnxruntime")
#: bittc_core.estimator.TTA_MODES, kept here so --help imports no torch (the tests compare them)
TTA_MODES = ("none", "flip")


def add_backend_flags(parser) -> None:
    parser.add_argument(
        "--backend",
        default="torch",
        choices=BACKENDS,
        help="network backend: torch (default) or onnxruntime (needs --onnx DIR)",
    )
    parser.add_argument(
        "--onnx",
        default=None,
        metavar="DIR",
        help="with --backend onnxruntime: a folder made by `bittc export --onnx DIR`",
    )


def backend_kwargs(args, method: str = "bittc") -> dict:
    """-> {"backend", "onnx", "weights"} for ``make_estimator`` / the geofence controller
    ({} for torch), checked."""
    if args.backend not in BACKENDS:
        raise CliError(f"--backend {args.backend!r}: expected one of {', '.join(BACKENDS)}")
    if args.backend == "torch":
        if args.onnx is not None:
            raise CliError("--onnx applies to --backend onnxruntime")
        return {}
    if method != "bittc":
        raise CliError(f"--backend onnxruntime runs the network, not {method!r}")
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        raise CliError("--backend onnxruntime needs onnxruntime: pip install -e '.[onnx]'") from None
    if args.onnx is None:
        raise CliError("--backend onnxruntime needs --onnx DIR (make it with `bittc export --onnx DIR`)")
    if getattr(args, "device", "auto") not in ("auto", "cpu"):
        raise CliError(f"--device {args.device}: the onnxruntime backend runs on the CPU")
    from bittc_core.checkpoint import DEFAULT_WEIGHTS

    # the export is checked against the weights asked for (the shipped ones by default)
    return {"backend": "onnxruntime", "onnx": args.onnx, "weights": args.weights or str(DEFAULT_WEIGHTS)}


#: the CLI's fovea when --fovea is not given (chosen by the closed-loop comparison in docs/closed_loop.md)
DEFAULT_FOVEA = "4"


def add_fovea_flag(parser, many: bool = False) -> None:
    """``--fovea ZOOM|off`` (``many``: several, a sweep dimension)."""
    what = "a second, magnified view of the same camera beside the wide one: focal x ZOOM, centred on the road ahead"
    if many:
        parser.add_argument(
            "--fovea",
            nargs="+",
            default=[DEFAULT_FOVEA],
            metavar="ZOOM|off",
            help=f"{what}; one or more settings (default {DEFAULT_FOVEA})",
        )
    else:
        parser.add_argument(
            "--fovea",
            default=DEFAULT_FOVEA,
            metavar="ZOOM|off",
            help=f"{what}; off: the wide view alone (default {DEFAULT_FOVEA})",
        )


def parse_fovea(text) -> float | None:
    """'off' -> None; a zoom -> float in [1, MAX_FOVEA_ZOOM]; anything else -> CliError naming it."""
    from sim.camera import check_fovea_zoom

    if text is None or str(text).strip().lower() == "off":
        return None
    try:
        zoom = float(text)
    except ValueError:
        raise CliError(f"--fovea {text!r}: expected a zoom (e.g. 2 or 4) or off") from None
    try:
        return check_fovea_zoom(zoom)
    except ValueError as e:
        raise CliError(f"--fovea {text!r}: {e}") from None
