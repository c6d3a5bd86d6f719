"""Layering: scenario validation imports no simulator stack, the scenery knows no world,
library errors name values (never flags) and the CLI prints them."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

from bittc_core.errors import BittcError, CliError, ConfigError

ROOT = Path(__file__).resolve().parents[1]
#: the library: everything but the command line
LIBRARY = [
    p
    for d in ("sim", "bittc_core", "scenarios", "controllers")
    for p in sorted((ROOT / d).rglob("*.py"))
    if "cli" not in p.relative_to(ROOT).parts
]
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z-]+")


def _imported(code: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT).stdout
    return out.strip()


def test_validating_a_scenario_imports_no_simulator_stack():
    code = (
        "import scenarios.spec, sys; print([m for m in ('gymnasium', 'cv2', 'pybullet', 'torch') if m in sys.modules])"
    )
    assert _imported(code) == "[]"
    code = (
        "import scenarios, sys; scenarios.bundled(); scenarios.load_file(scenarios.BUNDLED_DIR / 'ccrs.yaml'); "
        "print([m for m in ('gymnasium', 'cv2', 'pybullet', 'torch') if m in sys.modules])"
    )
    assert _imported(code) == "[]"


def test_the_scenery_does_not_import_the_world():
    assert _imported("import sim.scenery, sys; print('sim.world' in sys.modules)") == "False"


def test_the_scenery_is_data():
    import numpy as np

    from sim.scenery import RoadConfig, Scenery, build_scenery

    s = build_scenery(RoadConfig(x_start_m=-20.0, x_end_m=100.0), np.random.default_rng(0))
    assert isinstance(s, Scenery) and s.groups and s.textures
    used = {g.texture for g in s.groups} - {None}
    assert used <= set(s.textures)
    assert sum(len(g.shapes) for g in s.groups) > 10
    assert build_scenery(RoadConfig(x_start_m=-20.0, x_end_m=100.0), np.random.default_rng(0)) == s


def test_library_errors_are_not_cli_errors():
    from bittc_core.checkpoint import CheckpointError
    from bittc_core.estimator.base import EstimatorInputError
    from bittc_core.export.manifest import ExportError
    from sim.latency import LatencyError
    from sim.sweep.sweep import SweepError

    for cls in (ConfigError, CheckpointError, EstimatorInputError, ExportError, LatencyError, SweepError):
        assert issubclass(cls, BittcError) and not issubclass(cls, CliError), cls


def _raised_strings(tree: ast.AST):
    """(line, text) of the string parts of every ``raise X(...)``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call):
            for arg in node.exc.args:
                for sub in ast.walk(arg):
                    if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                        yield sub.lineno, sub.value


def test_library_code_neither_raises_cli_errors_nor_names_flags():
    found = []
    for path in LIBRARY:
        tree = ast.parse(path.read_text())
        rel = path.relative_to(ROOT)
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.ImportFrom)
                and node.module
                and (node.module.startswith("sim.cli") or any(a.name == "CliError" for a in node.names))
            ):
                found.append(f"{rel}:{node.lineno}: imports from {node.module}")
        found += [f"{rel}:{line}: {text!r}" for line, text in _raised_strings(tree) if FLAG.search(text)]
    assert not found, "\n".join(found)


def test_generation_config_names_the_field_and_the_cli_the_flag(tmp_path, capsys):
    from sim.cli import main
    from sim.datagen.generate import GenerationConfig

    for kw, field in (
        (dict(seed=-1), "seed -1"),
        (dict(clip_length=1), "clip_length 1"),
        (dict(ground_texture="gravel"), "ground_texture 'gravel'"),
    ):
        with pytest.raises(ConfigError, match=f"^{field}") as e:
            GenerationConfig(**kw)
        assert "--" not in str(e.value)
    assert main(["generate", "--out", str(tmp_path / "d"), "--samples", "1", "--seed", "0", "--clip-length", "1"]) == 2
    assert "bittc generate: error: --clip-length 1: must be in [2, 32]" in capsys.readouterr().err


def test_the_cli_prints_a_library_error_on_one_line_and_exits_2(tmp_path, capsys):
    from sim.cli import main

    missing = tmp_path / "missing.yaml"
    assert main(["run", str(missing), "--controller", "oracle", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"bittc run: error: {missing}") and err.count("\n") == 1 and "Traceback" not in err


def test_one_module_converts_between_tau_and_eta():
    import numpy as np
    import torch

    import sim.ground_truth
    from bittc_core.ttc import eta_to_tau, tau_to_eta

    assert not hasattr(sim.ground_truth, "tau_from_eta") and not hasattr(sim.ground_truth, "eta_from_tau")
    assert _imported("import bittc_core.ttc, sim.ground_truth, sys; print('torch' in sys.modules)") == "False"
    tau = np.array([0.5, np.inf, -np.inf, -0.3])
    eta = tau_to_eta(tau, 0.1)
    np.testing.assert_allclose(eta, [0.5 / 0.6, 1.0, 1.0, -0.3 / -0.2])
    assert tau_to_eta(float("inf"), 0.1) == 1.0 and tau_to_eta(0.9, 0.1) == pytest.approx(0.9)
    assert torch.equal(tau_to_eta(torch.tensor([np.inf, 0.9]), 0.1), torch.tensor([1.0, 0.9]))
    np.testing.assert_allclose(eta_to_tau(eta[:2], 0.1), [0.5, np.inf])


# --- one-way layers ----------------------------------------------------------------------
#: layer -> what its modules may import of ours (a layer above may import every layer below)
LAYERS = {
    "bittc_core": {"bittc_core"},
    "scenarios": {"bittc_core", "scenarios"},
    "controllers": {"bittc_core", "scenarios", "controllers"},
    "sim": {"bittc_core", "scenarios", "controllers", "sim"},
    "sim.cli": {"bittc_core", "scenarios", "controllers", "sim", "sim.cli"},
}
OURS = ("bittc_core", "scenarios", "controllers", "sim")


def _module(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _layer(module: str) -> str:
    return "sim.cli" if module == "sim.cli" or module.startswith("sim.cli.") else module.split(".")[0]


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every import of ours in the file, lazy ones inside functions too."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append((node.lineno, node.module))
    return [(n, m) for n, m in out if m.split(".")[0] in OURS]


def test_no_import_runs_back_up_a_layer():
    bad = []
    for d in OURS:
        for path in sorted((ROOT / d).rglob("*.py")):
            layer = _layer(_module(path))
            for line, mod in _imports(path):
                if _layer(mod) not in LAYERS[layer]:
                    bad.append(f"{path.relative_to(ROOT)}:{line} ({layer}) imports {mod}")
    assert not bad, "imports that run back up a layer:\n" + "\n".join(bad)


def test_the_layering_test_sees_a_bad_import(tmp_path):
    """The rule above on a made-up file of the network library importing the simulator."""
    fake = ROOT / "bittc_core" / "_layering_probe.py"
    fake.write_text("def f():\n    from sim.world import World\n")
    try:
        with pytest.raises(AssertionError, match="bittc_core/_layering_probe.py:2"):
            test_no_import_runs_back_up_a_layer()
    finally:
        fake.unlink()


def test_the_network_and_the_estimators_import_nothing_above_them():
    code = (
        "import bittc_core.model, bittc_core.estimator, sys; "
        "print([m for m in sys.modules if m.split('.')[0] in ('sim','controllers','scenarios')])"
    )
    assert _imported(code) == "[]"


def test_no_import_cycle_between_sim_modules():
    """A module-level or lazy import cycle inside sim (latency and its profile files, say)."""
    graph = {}
    for path in sorted((ROOT / "sim").rglob("*.py")):
        me = _module(path)
        graph[me] = {m for _, m in _imports(path) if m.startswith("sim.") and m != me}
    cycles = []

    def visit(node, stack):
        for nxt in sorted(graph.get(node, ())):
            if nxt in stack:
                cycles.append(" -> ".join([*stack[stack.index(nxt) :], nxt]))
            elif nxt not in seen:
                seen.add(nxt)
                visit(nxt, [*stack, nxt])

    seen = set()
    for start in sorted(graph):
        if start not in seen:
            seen.add(start)
            visit(start, [start])
    assert not cycles, "\n".join(cycles)


MAX_FUNCTION_LINES = 80


def test_no_function_outside_tests_is_longer_than_80_lines():
    """Long functions are split into named steps, each with one job."""
    long = []
    for pkg in ("bittc_core", "sim", "controllers", "scenarios", "examples", "bench"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    n = node.end_lineno - node.lineno + 1
                    if n > MAX_FUNCTION_LINES:
                        long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({n} lines)")
    assert not long, long
