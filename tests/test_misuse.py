"""A tool that cannot be misused: worker counts bounded or refused, output folders locked
while a run writes them, and impossible output paths refused with exit code 2."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bittc_core.errors import ConfigError
from bittc_core.parallel import LOCK_FILE, OutputLock, bounded_workers, max_workers
from sim.cli import main

ROOT = Path(__file__).resolve().parents[1]
IMPOSSIBLE = "/proc/bittc-cannot-write-here"


def test_workers_are_bounded_by_the_tasks_and_refused_when_absurd(capsys):
    assert bounded_workers(8, tasks=3) == 3
    assert "starting 3" in capsys.readouterr().err
    assert bounded_workers(1, tasks=0) == 1
    with pytest.raises(ConfigError, match=f"workers 500: more than {max_workers()}"):
        bounded_workers(500, tasks=1000)
    for bad in (0, -1, True, 2.0):
        with pytest.raises(ConfigError, match="workers"):
            bounded_workers(bad, tasks=4)


def test_sweep_and_generate_refuse_500_workers_before_starting_any(tmp_path, capsys):
    out = tmp_path / "sw"
    argv = ["sweep", "--suite", "CCRs-20", "--controllers", "oracle", "--workers", "500", "--out", str(out)]
    assert main(argv) == 2
    assert "workers 500" in capsys.readouterr().err and not out.exists()
    gen = tmp_path / "gen"
    assert (
        main(["generate", "--out", str(gen), "--split", "train", "--samples", "2", "--seed", "0", "--workers", "500"])
        == 2
    )
    assert "workers 500" in capsys.readouterr().err and not gen.exists()


def test_more_workers_than_runs_start_one_per_run(tmp_path, capsys):
    out = tmp_path / "sw"
    argv = ["sweep", "--suite", "CCRs-20", "CCRs-30", "--controllers", "oracle", "--latency", "fixed:0"]
    assert main([*argv, "--workers", "8", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "8 workers for 2 task(s): starting 2" in err


def test_a_folder_in_use_is_refused_with_the_holders_pid(tmp_path, capsys):
    sweep_out, gen_out = tmp_path / "sw", tmp_path / "gen"
    with OutputLock(sweep_out), OutputLock.beside(gen_out):
        argv = [
            "sweep",
            "--suite",
            "CCRs-20",
            "--controllers",
            "oracle",
            "--latency",
            "fixed:0",
            "--out",
            str(sweep_out),
        ]
        assert main(argv) == 2
        assert f"in use by a running process (pid {os.getpid()})" in capsys.readouterr().err
        assert main(["generate", "--out", str(gen_out), "--split", "train", "--samples", "1", "--seed", "0"]) == 2
        assert f"pid {os.getpid()}" in capsys.readouterr().err
    assert [p.name for p in sweep_out.iterdir()] == [LOCK_FILE]  # nothing else written
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == [".gen.lock"] and not gen_out.exists()
    # released: the same sweep now runs
    assert main(argv) == 0


def test_train_into_a_checkpoint_in_use_is_refused(tmp_path, capsys):
    out = tmp_path / "run" / "net.pt"
    with OutputLock(out.parent, name=".net.lock"):
        assert main(["train", "--data", "synthetic", "--config", "tiny", "--out", str(out), "--steps", "1"]) == 2
        assert f"pid {os.getpid()}" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "CCRs-20", "--controller", "oracle", "--out", IMPOSSIBLE],
        ["suite", "--controller", "oracle", "--scenarios", "CCRs-20", "--out", IMPOSSIBLE],
        ["sweep", "--suite", "CCRs-20", "--controllers", "oracle", "--out", IMPOSSIBLE],
        ["demo", "--out", IMPOSSIBLE],
        ["generate", "--out", IMPOSSIBLE, "--split", "train", "--samples", "1", "--seed", "0"],
        ["train", "--data", "synthetic", "--config", "tiny", "--out", f"{IMPOSSIBLE}/net.pt", "--steps", "1"],
        ["eval", "--scenarios", "CCRs-20", "--method", "bittc", "--out", f"{IMPOSSIBLE}/eval.json"],
        ["bench", "--fovea", "off", "--out", f"{IMPOSSIBLE}/bench.json"],
        ["profile", "--out", f"{IMPOSSIBLE}/p.yaml"],
        ["export", "--onnx", IMPOSSIBLE],
        [
            "weights",
            "zero",
            str(ROOT / "bittc_core/weights/bittc_default.pt"),
            "--layers",
            "cont_refine.out",
            "--out",
            f"{IMPOSSIBLE}/w.pt",
        ],
    ],
    ids=lambda a: a[0],
)
def test_an_impossible_output_path_is_refused_in_one_line(argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and IMPOSSIBLE in err and "Traceback" not in err
    assert not Path(IMPOSSIBLE).exists()
