"""The command line's consistency: every option documented, choices shown, one seed range,
library errors mapped to flags, eval's default output never replaced silently."""

import argparse

import pytest

from bittc_core.errors import CliError, ConfigError
from sim.cli import all_parsers, build_parser, main
from sim.cli.common import MAX_SEED, TTA_MODES, check_seed, flag_error


def _walk(parser, path=("bittc",)):
    """(command path, parser, action) of every option and positional, subcommands included."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _walk(sub, (*path, name))
        elif not isinstance(action, argparse._HelpAction):
            yield path, parser, action


def _formatted(parser, action) -> str:
    return parser._get_formatter()._format_action(action)


ACTIONS = list(_walk(build_parser()))


def test_every_subcommand_has_a_help_line():
    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help for a in action._choices_actions}
            assert set(helps) == set(action.choices) and all(helps.values()), helps


@pytest.mark.parametrize(
    "path, parser, action",
    [pytest.param(*row, id=" ".join((*row[0][1:], "/".join(row[2].option_strings) or row[2].dest))) for row in ACTIONS],
)
def test_every_option_has_a_help_text(path, parser, action):
    name = "/".join(action.option_strings) or action.dest
    assert action.help and action.help.strip() and action.help != argparse.SUPPRESS, f"{' '.join(path)} {name}"


def test_options_with_choices_show_them():
    with_choices = [(p, a) for _, p, a in ACTIONS if a.choices is not None]
    assert len(with_choices) >= 10  # --split, --backend, --device, --method, --tta, --stage ...
    for parser, action in with_choices:
        text = _formatted(parser, action)
        missing = [c for c in action.choices if str(c) not in text]
        assert not missing, f"{parser.prog} {action.option_strings}: {missing} not in {text!r}"


def _option(command: str, flag: str):
    return next((p, a) for path, p, a in ACTIONS if path[1:] == (command,) and flag in a.option_strings)


def test_enumerated_options_without_choices_list_their_values_in_the_help():
    import controllers
    import scenarios
    from bittc_core.model import CONFIGS
    from sim.cli.train_flags import STAGE_CHOICES
    from sim.textures import GROUND_STYLES, VEHICLE_STYLES

    expected = [(c, "--ground-texture", GROUND_STYLES) for c in ("run", "suite", "generate")]
    expected += [(c, "--vehicle-texture", VEHICLE_STYLES) for c in ("run", "suite", "generate")]
    expected += [(c, "--controller", tuple(controllers.REGISTRY)) for c in ("run", "suite")]
    expected += [
        ("sweep", "--controllers", tuple(controllers.REGISTRY)),
        ("sweep", "--suite", tuple(scenarios.SUITES)),
        ("eval", "--scenarios", tuple(scenarios.SUITES)),
        ("train", "--config", tuple(CONFIGS)),
        ("train", "--stage", STAGE_CHOICES),
    ]
    for command, flag, values in expected:
        parser, action = _option(command, flag)
        text = _formatted(parser, action)
        missing = [v for v in values if v not in text]
        assert not missing, f"bittc {command} {flag}: {missing} not in its help"


def test_the_cli_copy_of_the_tta_modes_is_the_estimators():
    from bittc_core.estimator import TTA_MODES as LIBRARY_TTA_MODES

    assert TTA_MODES == LIBRARY_TTA_MODES


def test_every_frame_stride_flag_names_the_controllers_default():
    from controllers.geofence import DEFAULT_FRAME_STRIDE

    strides = [(path, a) for path, _, a in ACTIONS if "--frame-stride" in a.option_strings]
    assert {path[1] for path, _ in strides} >= {"run", "suite", "sweep", "eval"}
    for path, action in strides:
        if path[1] == "train":  # the span of the dataset's pairs, in the network's frame intervals
            assert action.default == 1 and "as `bittc run --frame-stride N` feeds it" in action.help
            continue
        assert action.default is None and f"default {DEFAULT_FRAME_STRIDE}" in action.help, path


def test_every_seed_flag_has_the_same_bounds():
    seeds = [(path, a) for path, _, a in ACTIONS if "--seed" in a.option_strings]
    assert {path[1] for path, _ in seeds} == {"run", "suite", "generate", "train", "eval"}
    for path, action in seeds:
        assert action.type is int and "0 to 2^32 - 1" in action.help, path
    assert check_seed(0) == 0 and check_seed(MAX_SEED) == MAX_SEED
    for bad in (-1, MAX_SEED + 1):
        with pytest.raises(CliError, match=f"--seed {bad}: must be in \\[0, {MAX_SEED}\\]"):
            check_seed(bad)


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "CCRs-50", "--controller", "oracle", "--out", "OUT"],
        ["suite", "--scenarios", "CCRs-50", "--out", "OUT"],
        ["generate", "--out", "OUT", "--samples", "1"],
        ["eval", "--scenarios", "CCRs-50", "--method", "flow", "--out", "OUT/e.json"],
    ],
)
def test_a_seed_out_of_range_is_refused_by_every_subcommand(tmp_path, capsys, argv):
    argv = [str(tmp_path / "o") if a == "OUT" else a.replace("OUT", str(tmp_path)) for a in argv]
    assert main([*argv, "--seed", str(MAX_SEED + 1)]) == 2
    assert f"--seed {MAX_SEED + 1}: must be in [0, {MAX_SEED}]" in capsys.readouterr().err


def test_train_refuses_a_seed_out_of_range():
    from sim.cli.train_flags import check_train_flags

    args = build_parser().parse_args(
        ["train", "--data", "synthetic", "--config", "tiny", "--out", "m.pt", "--seed", str(MAX_SEED + 1)]
    )
    with pytest.raises(CliError, match="--seed"):
        check_train_flags(args)


def test_flag_error_names_the_flag_of_a_leading_field():
    flags = {"seed": "--seed", "output folder": "--out", "clip_length": "--clip-length"}
    assert str(flag_error(ConfigError("seed -1: must be >= 0"), flags)) == "--seed -1: must be >= 0"
    assert str(flag_error(ConfigError("output folder 'x': not writable"), flags)) == "--out 'x': not writable"
    assert str(flag_error(ConfigError("clip_length: too short"), flags)) == "--clip-length: too short"
    assert isinstance(flag_error(ConfigError("seed 1"), flags), CliError)
    other = ConfigError("seeds 3: not a field of this command")
    assert flag_error(other, flags) is other  # "seeds" is not "seed": printed as it is


def test_eval_refuses_to_replace_its_default_output(tmp_path, monkeypatch, capsys):
    from sim.cli import eval_cmd

    monkeypatch.chdir(tmp_path)
    argv = ["eval", "--data", "synthetic", "--method", "oracle", "--split", "val"]
    assert eval_cmd._check(build_parser().parse_args(argv)).name == "eval_oracle_val.json"
    (tmp_path / "eval_oracle_val.json").write_text("{}")
    with pytest.raises(CliError, match="'eval_oracle_val.json' exists .*pass --out eval_oracle_val.json"):
        eval_cmd._check(build_parser().parse_args(argv))
    assert main([*argv, "--limit", "1"]) == 2 and "exists" in capsys.readouterr().err
    assert (tmp_path / "eval_oracle_val.json").read_text() == "{}"
    explicit = eval_cmd._check(build_parser().parse_args([*argv, "--out", "eval_oracle_val.json"]))
    assert explicit.name == "eval_oracle_val.json"  # named on purpose: replaced


def test_bench_refuses_a_config_with_weights():
    from sim.cli import bench_cmd

    args = build_parser().parse_args(["bench", "--config", "tiny", "--weights", "w.pt"])
    with pytest.raises(CliError, match="--config 'tiny' with --weights"):
        bench_cmd.check_common(args)
    assert main(["bench", "--config", "tiny", "--weights", "w.pt"]) == 2


def test_help_wraps_at_spaces_so_hyphenated_names_stay_whole(monkeypatch):
    """At 80 columns no option help, description or usage splits a name (a model config,
    a scenario, a flag) at one of its hyphens."""
    import re

    monkeypatch.setenv("COLUMNS", "80")
    split = [
        (parser.prog, line)
        for parser in all_parsers(build_parser())
        for line in parser.format_help().splitlines()
        if re.search(r"[A-Za-z0-9]-$", line)
    ]
    assert not split, split
