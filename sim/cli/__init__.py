"""The `bittc` command line.

Each subcommand lives in its own module of this package and exposes
``add_parser(subparsers) -> argparse.ArgumentParser`` and ``run(args) -> int``.
The library raises :class:`bittc_core.errors.ConfigError` (naming the bad value) and the
subcommands :class:`CliError` (naming the flag); ``main`` prints either on one line to
stderr and exits with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import textwrap

# The simulator's numpy work is small; one BLAS thread keeps OpenBLAS's spinning workers
# from contending with the estimator's torch threads (measured: +5 ms per call at K = 4 on
# 2 cores). Set before anything imports numpy.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from bittc_core.errors import BittcError

#: subcommand name -> module; heavy imports (torch, pybullet) stay inside each run()
COMMANDS: dict[str, str] = {
    "run": "sim.cli.run_cmd",
    "scenarios": "sim.cli.scenarios_cmd",
    "suite": "sim.cli.suite_cmd",
    "generate": "sim.cli.generate_cmd",
    "data": "sim.cli.data_cmd",
    "train": "sim.cli.train_cmd",
    "eval": "sim.cli.eval_cmd",
    "bench": "sim.cli.bench_cmd",
    "predict": "sim.cli.predict_cmd",
    "profiles": "sim.cli.profiles_cmd",
    "profile": "sim.cli.profile_cmd",
    "export": "sim.cli.export_cmd",
    "sweep": "sim.cli.sweep_cmd",
    "demo": "sim.cli.demo_cmd",
    "weights": "sim.cli.weights_cmd",
    "compare": "sim.cli.compare_cmd",
}


class _HelpFormatter(argparse.HelpFormatter):
    """Wraps help and descriptions at spaces only, so that a hyphenated name (a model
    config, a scenario, a flag) stays whole on one line."""

    def _split_lines(self, text: str, width: int) -> list[str]:
        return textwrap.wrap(self._whitespace_matcher.sub(" ", text).strip(), width, break_on_hyphens=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        text = self._whitespace_matcher.sub(" ", text).strip()
        return textwrap.fill(text, width, initial_indent=indent, subsequent_indent=indent, break_on_hyphens=False)


class _RawDescriptionHelpFormatter(argparse.RawDescriptionHelpFormatter, _HelpFormatter):
    """``_HelpFormatter`` for a command whose description keeps its own line breaks."""


def all_parsers(parser: argparse.ArgumentParser):
    """``parser``, then every subcommand's parser, depth first."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from all_parsers(sub)


def _wrap_at_spaces(parser: argparse.ArgumentParser) -> None:
    """Give ``parser`` and every subcommand's parser the formatters above, in place of
    argparse's two (any other formatter a command sets stays)."""
    replace = {
        argparse.HelpFormatter: _HelpFormatter,
        argparse.RawDescriptionHelpFormatter: _RawDescriptionHelpFormatter,
    }
    for p in all_parsers(parser):
        p.formatter_class = replace.get(p.formatter_class, p.formatter_class)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bittc",
        description="Closed-loop camera collision-warning simulator built around Binary TTC.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in COMMANDS.values():
        module = importlib.import_module(module_name)
        p = module.add_parser(sub)
        p.set_defaults(_run=module.run)
    _wrap_at_spaces(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # argparse has printed the usage and the error (or --help)
        return int(exit_.code or 0)
    try:
        return int(args._run(args) or 0)
    except BittcError as err:  # CliError (a flag) or a library error (a value)
        print(f"bittc {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"bittc {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
