"""Bad inputs and faults for every subcommand of ``pacto``, generated (not hand-picked).

A :class:`Scenario` is a command line (``argv`` of :func:`pacto_ng.cli.main`), optional
environment, an optional ``prepare(base, work)`` that damages a copy of a finished run or
writes a bad input file, and what is allowed: an exit code of 2 (bad input: one line naming
``names``), 1 (a numerical failure the run reports) or 0 (the input is valid after all: the
run completes and writes finite outputs).  ``quick`` scenarios are refused before any mesh is
built; they form the default suite's subset.

The parameter scenarios iterate over **every** parameter of the toolkit (``Parameters.names``)
and every case option, with values generated from the parameter's type.
"""
from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

#: the finished runs the scenarios start from (built once per session, see conftest.py):
#: a small pa-inverter (pressure, linear) and a small cantilever (force, linear)
BASE_RUNS = {
    "pa": ["run", "pa-inverter", "--nelx", "20", "--nely", "10", "--set", "iterations=3"],
    "cant": ["run", "cantilever", "--nelx", "12", "--nely", "4", "--set", "iterations=3"],
}
#: the mesh and iteration options that make a scenario's run small
SMALL = {"pa-inverter": ["--nelx", "20", "--nely", "10"], "cantilever": ["--nelx", "12", "--nely", "4"],
         "inverter": ["--nelx", "12", "--nely", "6"], "mm-gripper": ["--nelx", "12", "--nely", "6"]}
ITER = ["--set", "iterations=2"]


def pa_small() -> list[str]:
    """The small pa-inverter's case and mesh options."""
    return ["pa-inverter", *SMALL["pa-inverter"]]


@dataclass
class Scenario:
    id: str
    argv: list[str]
    names: tuple[str, ...] = ()  # a refusal (exit 2) must name one of these
    exits: tuple[int, ...] = (0, 1, 2)
    env: dict = field(default_factory=dict)
    prepare: Callable | None = None  # prepare(base: dict[str, Path], work: Path) -> None
    quick: bool = False  # refused before meshing: in the default suite
    early: bool = False  # refused by the parameters' own checks (run in the test's process)
    timeout: float = 180.0


def bad_values(default) -> list[tuple[str, bool]]:
    """``(text, quick)``: values of the parameter's type that a user could mistype; ``quick``
    ones are refused by the declared type check alone."""
    if isinstance(default, bool):
        return [("maybe", True), ("", True), ("2", True), ("1.5", True)]
    if isinstance(default, int):
        return [("nan", True), ("inf", True), ("-inf", True), ("2.5", True), ("abc", True),
                ("", True), ("1e20", False), ("0", False), ("-1", False)]
    if isinstance(default, float):
        return [("nan", True), ("inf", True), ("-inf", True), ("abc", True), ("", True),
                ("1e400", True), ("0", False), ("-1", False), ("1e308", False),
                ("-1e308", False), ("1e-308", False)]
    return [("", False), ("zzz", False), ("x" * 300, False), ("a|b", False)]


def parameter_scenarios() -> list[Scenario]:
    """Every parameter of the toolkit on the pa-inverter (it reads them all), and each case's
    own options on its case."""
    from pacto_ng.case import get_case
    from pacto_ng.params import InputError

    def refused(case, name, text):
        try:
            case.resolve(case.defaults.with_overrides({name: text}))
        except InputError:
            return True
        return False

    out = []
    for case_name, only in (("pa-inverter", None), ("cantilever", ("load_width",)),
                            ("inverter", ("k_in", "load_width")),
                            ("mm-gripper", ("volfrac2", "E2"))):
        case = get_case(case_name)
        params = case.defaults
        for i, name in enumerate(params.keys()):
            if only is not None and name not in only:
                continue
            mesh = [] if name in ("nelx", "nely", "maxh", "unit_elements", "order") \
                else SMALL[case_name]
            it = [] if name == "iterations" else ITER
            values = bad_values(getattr(params, name))
            quick_values = [text for text, quick in values if quick]
            for text, _ in values:
                # the default suite takes one type-refused value of each parameter, in turn
                quick = bool(quick_values) and text == quick_values[i % len(quick_values)]
                out.append(Scenario(f"set-{case_name}-{name}={text[:12]}",
                                    ["run", case_name, *mesh, *it, "--set", f"{name}={text}"],
                                    names=(name,), quick=quick,
                                    early=refused(case, name, text)))
    return out


def option_scenarios() -> list[Scenario]:
    """The direct options of run, evaluate, check-gradients and sweep, and case naming."""
    pa = ["pa-inverter", *SMALL["pa-inverter"], *ITER]
    out = []
    direct = {"--load": ["0", "-5", "1e308", "nan", "inf", "abc"],
              "--iterations": ["0", "-1", "1e20", "abc", "2.5"],
              "--nelx": ["-3", "1e20", "abc", "100000"], "--nely": ["-3", "0", "abc"],
              "--maxh": ["0", "-1", "nan", "abc", "1e-5", "1e9"],
              "--order": ["-1", "7", "abc"], "--model": ["foo", ""],
              "--optimizer": ["foo", ""]}
    for opt, values in direct.items():
        for v in values:
            name = opt[2:]
            if opt in ("--nelx", "--nely", "--maxh"):
                base = ["pa-inverter", *ITER]
            elif opt == "--iterations":
                base = ["pa-inverter", *SMALL["pa-inverter"]]
            else:
                base = pa
            quick = v not in ("100000", "1e-5", "1e9") and (opt, v) not in (
                ("--iterations", "0"), ("--nely", "0"))
            out.append(Scenario(f"run{opt}={v}", ["run", *base, opt, v],
                                names=(name, opt), quick=quick))
    for argv, names in (
            (["run", "no-such-case"], ("no-such-case",)),
            (["run", "missing/case_file.py"], ("case_file.py",)),
            (["run", *pa, "--set", "volfrac"], ("--set",)),
            (["run", *pa, "--set", "nosuch=1"], ("nosuch",)),
            (["run", *pa, "--set", "=1"], ("--set",)),
            (["run", *pa, "--set", "volfrac=0.3=4"], ("volfrac",)),
            (["run", *pa, "--bogus"], ("--bogus",)),
            (["run"], ("case",)),
            (["evaluate", *pa], ("--density",)),
            (["check-gradients", *pa, "--seed", "-1"], ("--seed", "seed")),
            (["check-gradients", *pa, "--seed", "abc"], ("--seed", "seed")),
            (["check-gradients", *pa, "--tol", "nan"], ("--tol", "tol")),
            (["check-gradients", *pa, "--tol", "-1"], ("--tol", "tol")),
            (["sweep", "pa-inverter", "--loads", ""], ("--loads", "loads")),
            (["sweep", "pa-inverter", "--loads", "a,b"], ("--loads", "loads")),
            (["sweep", "pa-inverter", "--loads", "1,nan"], ("--loads", "loads")),
            (["sweep", "pa-inverter", "--loads", "-1"], ("--loads", "loads", "load")),
            (["sweep", "pa-inverter", "--loads", "1", "--models", "foo"], ("--models", "model")),
            (["sweep", "pa-inverter", "--loads", "1", "--workers", "-1"], ("--workers",)),
            (["nosuchcommand"], ("nosuchcommand", "command")),
    ):
        out.append(Scenario("cli-" + "-".join(a.strip("-")[:10] for a in argv[:1] + argv[-2:]),
                            argv, names=names, exits=(2,), quick=True))
    for value in ("64", "0", "-1", "99999999999999999999", "abc", "", "1.5"):
        out.append(Scenario(f"env-PACTO_THREADS={value}", ["run", *pa],
                            names=("PACTO_THREADS",), env={"PACTO_THREADS": value},
                            exits=(0, 2), quick=value not in ("", "64")))
    return out


# -- damaged run folders ----------------------------------------------------------------------
def _copy(base: Path, work: Path) -> Path:
    run = work / "run"
    shutil.copytree(base, run)
    return run


def _write(rel: str, data: bytes | str | None):
    def prepare(base, work):
        run = _copy(base["pa"], work)
        fp = run / rel
        if data is None:
            fp.unlink()
        elif isinstance(data, bytes):
            fp.write_bytes(data)
        else:
            fp.write_text(data)
    return prepare


def _truncate(rel: str, keep: float):
    def prepare(base, work):
        run = _copy(base["pa"], work)
        raw = (run / rel).read_bytes()
        (run / rel).write_bytes(raw[:int(len(raw) * keep)])
    return prepare


def _edit_params(change: Callable[[dict], object]):
    def prepare(base, work):
        run = _copy(base["pa"], work)
        info = change(json.loads((run / "params.json").read_text()))
        (run / "params.json").write_text(json.dumps(info))
    return prepare


def _foreign_checkpoint(base, work):
    run = _copy(base["pa"], work)
    shutil.copy(base["cant"] / "checkpoint.npz", run / "checkpoint.npz")


def _set(info, key, value):
    info["params"][key] = value
    return info


DAMAGE = {
    "no-params": _write("params.json", None),
    "empty-params": _write("params.json", b""),
    "garbage-params": _write("params.json", b"\x00\xffnot json"),
    "list-params": _write("params.json", "[]"),
    "null-params": _write("params.json", "null"),
    "no-case-key": _edit_params(lambda i: {k: v for k, v in i.items() if k != "case"}),
    "unknown-case": _edit_params(lambda i: {**i, "case": "no-such-case"}),
    "case-not-str": _edit_params(lambda i: {**i, "case": 5}),
    "no-params-key": _edit_params(lambda i: {k: v for k, v in i.items() if k != "params"}),
    "params-not-dict": _edit_params(lambda i: {**i, "params": [1, 2]}),
    "unknown-key": _edit_params(lambda i: _set(i, "no_such_parameter", 1)),
    "wrong-type": _edit_params(lambda i: _set(i, "volfrac", "abc")),
    "wrong-type-int": _edit_params(lambda i: _set(i, "nelx", 2.5)),
    "out-of-range": _edit_params(lambda i: _set(i, "volfrac", 7.0)),
    "other-mesh": _edit_params(lambda i: _set(i, "nelx", 13)),
    "missing-case-file": _edit_params(lambda i: {**i, "case_file": "/nonexistent/case.py"}),
    "no-checkpoint": _write("checkpoint.npz", None),
    "empty-checkpoint": _write("checkpoint.npz", b""),
    "garbage-checkpoint": _write("checkpoint.npz", b"PK\x03\x04garbage" * 10),
    "half-checkpoint": _truncate("checkpoint.npz", 0.5),
    "foreign-checkpoint": _foreign_checkpoint,
    "no-summary": _write("summary.json", None),
    "garbage-summary": _write("summary.json", b"{\"objective\": "),
    "summary-list": _write("summary.json", "[1, 2]"),
}


def folder_scenarios() -> list[Scenario]:
    """resume, analyse, export, compare and evaluate (from a checkpoint) on damaged copies of a
    finished run, and on paths that are no run at all."""
    out = []
    commands = {"resume": lambda d: ["resume", d],
                "analyse": lambda d: ["analyse", d, "--pressures", "1e4", "--kinds", "fixed"],
                "export": lambda d: ["export", d, "--format", "vtk"],
                "compare": lambda d: ["compare", d, d],
                "evaluate": lambda d: ["evaluate", "pa-inverter", *SMALL["pa-inverter"],
                                       "--density", d + "/checkpoint.npz"]}
    for damage, prepare in DAMAGE.items():
        for cmd, argv in commands.items():
            out.append(Scenario(f"{cmd}-{damage}", argv("{work}/run"), exits=(0, 1, 2),
                                names=("params.json", "checkpoint.npz", "summary.json", "run"),
                                prepare=prepare))
    for cmd, argv in commands.items():
        for what, path in (("missing", "{work}/nothing"), ("file", "{work}/afile"),
                           ("empty", "{work}/empty")):
            def prepare(base, work):
                (work / "afile").write_text("x")
                (work / "empty").mkdir()
            out.append(Scenario(f"{cmd}-{what}-folder", argv(path), exits=(2,),
                                names=("nothing", "afile", "empty"), prepare=prepare,
                                quick=True))
    return out


# -- density files of evaluate ----------------------------------------------------------------
N_PA = 20 * 10  # elements of the small pa-inverter


def _density(name: str, make: Callable[[], object]):
    def prepare(base, work):
        data = make()
        fp = work / name
        if isinstance(data, (bytes, str)):
            (fp.write_bytes if isinstance(data, bytes) else fp.write_text)(data)
        else:
            np.save(fp, data)
    return prepare


DENSITIES = {
    "empty.txt": lambda: "",
    "garbage.txt": lambda: "one two three\n",
    "garbage.npy": lambda: b"\x93NUMPY garbage",
    "short.npy": lambda: np.full(N_PA - 1, 0.5),
    "long.npy": lambda: np.full(N_PA + 1, 0.5),
    "column3d.npy": lambda: np.full((10, 20, 1), 0.5),
    "grid3d.npy": lambda: np.full((2, 10, 20), 0.5),
    "complex.npy": lambda: np.full(N_PA, 0.5 + 0.1j),
    "nan.npy": lambda: np.r_[np.full(N_PA - 1, 0.5), np.nan],
    "inf.npy": lambda: np.r_[np.full(N_PA - 1, 0.5), np.inf],
    "above-one.npy": lambda: np.full(N_PA, 1.5),
    "negative.npy": lambda: np.full(N_PA, -0.5),
    "strings.npy": lambda: np.array(["a"] * N_PA),
    "object.npy": lambda: np.array([None] * N_PA, dtype=object),
    "bool.npy": lambda: np.ones(N_PA, dtype=bool),
    "scalar.npy": lambda: np.float64(0.5),
    "nan.csv": lambda: "\n".join(["0.5"] * (N_PA - 1) + ["nan"]),
    "ragged.csv": lambda: "0.5,0.5\n0.5\n",
    "design.vtu": lambda: "<VTKFile>not really</VTKFile>",
    "unknown.xyz": lambda: "0.5\n",
}


def density_scenarios() -> list[Scenario]:
    out = []
    for name, make in DENSITIES.items():
        out.append(Scenario(f"evaluate-density-{name}",
                            ["evaluate", "pa-inverter", *SMALL["pa-inverter"], "--density",
                             "{work}/" + name], exits=(0, 2), names=(name,),
                            prepare=_density(name, make)))
    out.append(Scenario("evaluate-density-missing",
                        ["evaluate", *pa_small(), "--density", "{work}/none.npy"],
                        exits=(2,), names=("none.npy",), quick=True))
    return out


# -- files that must not be overwritten -------------------------------------------------------
def _existing_run(base, work):
    _copy(base["pa"], work)


def _user_file(base, work):
    (work / "mine.py").write_text("# a user's file\n")


def overwrite_scenarios() -> list[Scenario]:
    pa = ["pa-inverter", *SMALL["pa-inverter"], *ITER]
    return [
        Scenario("run-into-existing-run", ["run", *pa, "--out", "{work}/run"], exits=(2,),
                 names=("--overwrite", "resume"), prepare=_existing_run),
        Scenario("run-other-case-into-run", ["run", "cantilever", *SMALL["cantilever"], *ITER,
                                             "--out", "{work}/run"], exits=(2,),
                 names=("--overwrite", "resume"), prepare=_existing_run),
        Scenario("evaluate-into-existing-run", ["evaluate", *pa, "--density",
                                                "{work}/run/checkpoint.npz", "--out",
                                                "{work}/run"], exits=(2,),
                 names=("--overwrite", "--out"), prepare=_existing_run),
        Scenario("new-over-user-file", ["new", "{work}/mine.py"], exits=(2,),
                 names=("mine.py",), prepare=_user_file, quick=True),
        Scenario("new-in-missing-folder", ["new", "{work}/no/such/dir/case.py"], exits=(2,),
                 names=("case.py", "no/such/dir"), quick=True),
        # the base run is 3 iterations old: grey, no solid at 0.5; 0.2 keeps a part
        Scenario("export-into-missing-folder", ["export", "{work}/run", "--format", "stl",
                                                "--threshold", "0.2",
                                                "--out", "{work}/no/such/dir/part.stl"],
                 exits=(0, 2), names=("part.stl", "no/such/dir"), prepare=_existing_run),
    ]


def all_scenarios() -> list[Scenario]:
    return (parameter_scenarios() + option_scenarios() + folder_scenarios()
            + density_scenarios() + overwrite_scenarios())
