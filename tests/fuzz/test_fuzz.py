"""The fuzz suite: bad inputs and faults across every subcommand (tests/fuzz/scenarios.py).

Each scenario must end with an allowed exit code (2: bad input, 1: a numerical failure the run
reports, 0: valid after all), at most two lines on stderr, no traceback, a refusal that names
what was wrong, no NaN or infinity in any file written, and every earlier run folder
byte-identical afterwards.

The default suite runs the ``quick`` scenarios (refused before any mesh is built) in this
process; ``pytest -m slow`` runs every scenario: those refused by the parameters' own checks in
this process, every other one in a process of its own with a time limit (a hang fails).
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fuzz.scenarios import BASE_RUNS, Scenario, all_scenarios

SCENARIOS = all_scenarios()
QUICK = [s for s in SCENARIOS if s.quick]


def test_the_suite_generates_enough_scenarios():
    assert len(SCENARIOS) >= 200
    assert len({s.id for s in SCENARIOS}) == len(SCENARIOS)


def _digest(folder: Path) -> dict:
    """Every file's SHA-256 but the folder lock's (.pacto.lock holds the PID of the last process
    that took the lock: no data of the run)."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name != ".pacto.lock"}


@pytest.fixture(scope="session")
def base_runs(tmp_path_factory):
    """The finished runs the damaged-folder scenarios copy (never written to afterwards)."""
    from pacto_ng.cli import main

    root = tmp_path_factory.mktemp("fuzz-base")
    runs = {}
    for key, argv in BASE_RUNS.items():
        assert main([*argv, "--quiet", "--out", str(root / key)]) == 0
        runs[key] = root / key
    return runs


def _argv(s: Scenario, work: Path) -> list[str]:
    argv = [a.replace("{work}", str(work)) for a in s.argv]
    if argv and argv[0] in ("run", "evaluate", "check-gradients") and "--out" not in argv:
        argv += ["--out", str(work / "out")]
    return argv


def _no_constant(token):
    raise ValueError(f"non-finite token {token}")


def _check_outputs(work: Path, before: dict):
    """Every JSON file the command wrote strict (no NaN/Infinity), every CSV it wrote free of
    non-finite numbers (``before``: the digests of what the scenario itself prepared)."""
    after = _digest(work)
    written = [work / name for name, digest in after.items() if before.get(name) != digest]
    for fp in (f for f in written if f.suffix == ".json"):
        json.loads(fp.read_text(), parse_constant=_no_constant)
    for fp in (f for f in written if f.suffix == ".csv"):
        for cell in fp.read_text().replace("\n", ",").split(","):
            try:
                value = float(cell)
            except ValueError:
                continue
            assert math.isfinite(value), f"{fp.name}: {cell}"


def _check(s: Scenario, code: int, stderr: str, work: Path, prepared: dict):
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert "Traceback" not in stderr, stderr[-3000:]
    assert code in s.exits, f"exit {code}, allowed {s.exits}: {stderr[-600:]}"
    assert len(lines) <= 2, "\n".join(lines[-10:])
    if code == 2 and s.names:
        assert any(n.lower() in stderr.lower() for n in s.names), \
            f"the refusal does not name any of {s.names}: {stderr.strip()}"
    _check_outputs(work, prepared)


def _prepare(s: Scenario, work: Path, base_runs):
    if s.prepare is not None:
        s.prepare(base_runs, work)


def _in_process(s: Scenario, work: Path, base: dict, monkeypatch, capsys):
    from pacto_ng.cli import main

    _prepare(s, work, base)
    prepared = _digest(work)
    before = {k: _digest(v) for k, v in base.items()}
    for key, value in s.env.items():
        monkeypatch.setenv(key, value)
    monkeypatch.chdir(work)
    try:
        code = main(_argv(s, work))
    except SystemExit as exc:  # argparse: usage errors
        code = exc.code
    _check(s, code, capsys.readouterr().err, work, prepared)
    assert {k: _digest(v) for k, v in base.items()} == before


@pytest.mark.parametrize("s", QUICK, ids=[s.id for s in QUICK])
def test_quick_scenario(s, tmp_path, monkeypatch, capsys, request):
    base = request.getfixturevalue("base_runs") if s.prepare is not None else {}
    _in_process(s, tmp_path, base, monkeypatch, capsys)


@pytest.mark.slow
@pytest.mark.parametrize("s", SCENARIOS, ids=[s.id for s in SCENARIOS])
def test_scenario(s, tmp_path, base_runs, monkeypatch, capsys):
    """Every scenario: those the parameters' own checks refuse in this process, the others in
    a process of their own with a time limit."""
    if s.early or s.quick:
        _in_process(s, tmp_path, base_runs, monkeypatch, capsys)
        return
    _prepare(s, tmp_path, base_runs)
    prepared = _digest(tmp_path)
    before = {k: _digest(v) for k, v in base_runs.items()}
    inside = {k: _digest(tmp_path / k) for k in ("run",) if (tmp_path / k).is_dir()}
    env = {**os.environ, **s.env}
    try:
        done = subprocess.run([sys.executable, "-m", "pacto_ng.cli", *_argv(s, tmp_path)],
                              cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=s.timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"hang: no end within {s.timeout} s")
    _check(s, done.returncode, done.stderr, tmp_path, prepared)
    assert {k: _digest(v) for k, v in base_runs.items()} == before
    if done.returncode == 2:  # a refused command changes nothing it was pointed at
        assert {k: _digest(tmp_path / k) for k in inside} == inside
