"""pacto sweep: grid, folder names, resuming, the table and plot, Dask execution, bad input."""
import csv
import json
import sys

import pytest

from pacto_ng import sweep, sweep_plan, sweep_table
from pacto_ng.cli import main
from pacto_ng.params import InputError, Parameters

TINY = ["--nelx", "12", "--nely", "4", "--iterations", "3"]


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def summary(folder):
    return json.loads((folder / "summary.json").read_text())


# -- pure functions --------------------------------------------------------------------------
def test_parse_loads():
    assert sweep_plan.parse_loads("1e5, 1e6,1e7") == (1e5, 1e6, 1e7)
    assert sweep_plan.parse_loads("2.5") == (2.5,)


@pytest.mark.parametrize("text", ["", " , ", "1,abc", "0", "-1", "inf", "nan", "1,,2", "1,1.0"])
def test_parse_loads_rejects(text):
    with pytest.raises(InputError, match="--loads"):
        sweep_plan.parse_loads(text)


def test_parse_models():
    assert sweep_plan.parse_models(None, "linear") == ("linear",)
    assert sweep_plan.parse_models("linear, neohookean", "gnl") == ("linear", "neohookean")
    for bad in ("rubber", "", "linear,linear", "linear,"):
        with pytest.raises(InputError, match="--models"):
            sweep_plan.parse_models(bad, "linear")


@pytest.mark.parametrize("load, label", [(1e5, "1e5"), (2.5e5, "2.5e5"), (1.0, "1e0"),
                                         (0.5, "5e-1"), (123456.7, "1.23457e5"), (1e-7, "1e-7")])
def test_load_label(load, label):
    assert sweep_plan.load_label(load) == label


def test_grid_and_folder_names():
    runs = sweep_plan.sweep_grid(("linear", "neohookean"), (1e5, 1e6))
    assert [(r.model, r.load, r.folder) for r in runs] == [
        ("linear", 1e5, "linear-1e5"), ("linear", 1e6, "linear-1e6"),
        ("neohookean", 1e5, "neohookean-1e5"), ("neohookean", 1e6, "neohookean-1e6")]
    p = sweep_plan.run_parameters(Parameters(), runs[3])
    assert p.model == "neohookean" and p.load == 1e6


def test_run_status_and_parameter_check(tmp_path):
    params = Parameters(iterations=3)
    assert sweep_plan.run_status(tmp_path) == "new"
    (tmp_path / "params.json").write_text(json.dumps({"case": "mbb", "params": params.to_dict()}))
    assert sweep_plan.run_status(tmp_path) == "new"  # stopped before its first checkpoint
    (tmp_path / "checkpoint.npz").write_bytes(b"")
    (tmp_path / "summary.json").write_text('{"objective": 1.')  # cut short while writing
    assert sweep_plan.run_status(tmp_path) == "resume"
    sweep_plan.check_same_parameters(tmp_path, params, "resume")
    with pytest.raises(InputError, match="iterations = 3.*iterations = 4"):
        sweep_plan.check_same_parameters(tmp_path, Parameters(iterations=4), "resume")
    (tmp_path / "summary.json").write_text(json.dumps({"objective": 1.0,
                                                       "parameters": params.to_dict()}))
    assert sweep_plan.run_status(tmp_path) == "done"
    sweep_plan.check_same_parameters(tmp_path, params, "done")
    with pytest.raises(InputError, match="volfrac"):
        sweep_plan.check_same_parameters(tmp_path, Parameters(iterations=3, volfrac=0.3), "done")


def test_parameter_check_compares_what_a_run_was_asked_for(tmp_path):
    """A run stores what ``--model auto`` and ``load_ramp=-1`` resolved to (here wang and a
    ramp of 37) and what was asked for (``model_choice``/``load_ramp_choice.requested``): the
    same sweep again finds it its own; another request is refused naming the parameter."""
    asked = Parameters(model="auto", load_ramp=-1, iterations=3)
    resolved = asked.replace(model="wang", load_ramp=37)
    (tmp_path / "summary.json").write_text(json.dumps({
        "objective": 1.0, "parameters": resolved.to_dict(),
        "model_choice": {"requested": "auto", "chosen": "wang"},
        "load_ramp_choice": {"requested": -1, "chosen": 37}}))
    sweep_plan.check_same_parameters(tmp_path, asked, "done")
    with pytest.raises(InputError, match="load_ramp = -1, this sweep has load_ramp = 0"):
        sweep_plan.check_same_parameters(tmp_path, asked.replace(load_ramp=0), "done")
    with pytest.raises(InputError, match="model = 'auto', this sweep has model = 'wang'"):
        sweep_plan.check_same_parameters(tmp_path, asked.replace(model="wang"), "done")


def _fake_summary(folder, **kw):
    folder.mkdir(parents=True, exist_ok=True)
    data = dict(objective=2.0, objective_name="output", output_displacement=-1e-4,
                load_reached=1e5, load_factor_reached=1.0, converged=True, stopped="converged",
                iterations=7, wall_time_s=3.5)
    data.update(kw)
    (folder / "summary.json").write_text(json.dumps(data))


def test_table_rows_of_finished_failed_and_missing_runs(tmp_path):
    runs = sweep_plan.sweep_grid(("neohookean",), (1e5, 1e6, 1e7, 1e8))
    _fake_summary(tmp_path / runs[0].folder)
    _fake_summary(tmp_path / runs[1].folder, converged=False, stopped="newton",
                  load_reached=4e5, load_factor_reached=0.4)
    # the optimisation ended normally but the final analysis of the design failed
    _fake_summary(tmp_path / runs[2].folder, converged=True, stopped="iterations",
                  load_reached=5e6, load_factor_reached=0.5)
    rows = sweep_table.collect_table(tmp_path, runs, errors={runs[3].folder: "RuntimeError: boom"})
    ok, newton, final, missing = rows
    assert ok["converged"] is True and ok["load_reached"] == 1e5 and ok["iterations"] == 7
    assert newton["converged"] is False and newton["load_reached"] == 4e5
    assert newton["stopped"] == "newton" and newton["objective"] == 2.0
    assert final["converged"] is False and final["stopped"] == "newton"
    assert missing["converged"] is False and missing["stopped"] == "error"
    assert missing["objective"] is None and missing["load"] == 1e8

    sweep_table.write_csv(tmp_path / "sweep.csv", rows)
    table = read_csv(tmp_path / "sweep.csv")
    assert tuple(table[0]) == sweep_table.COLUMNS
    assert [r["converged"] for r in table] == ["true", "false", "false", "false"]
    assert float(table[1]["load_reached"]) == 4e5 and table[1]["folder"] == "neohookean-1e6"
    assert table[3]["objective"] == "" and table[3]["stopped"] == "error"

    sweep_table.plot_sweep(tmp_path / "sweep.png", rows, "test", "N")
    assert (tmp_path / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_plot_without_output_displacement(tmp_path):
    rows = [dict(model=m, load=f, objective=f * f * k, output_displacement=None,
                 stopped="iterations")
            for k, m in enumerate(("linear", "gnl"), 1) for f in (1.0, 10.0)]
    sweep_table.plot_sweep(tmp_path / "p.png", rows)
    assert (tmp_path / "p.png").stat().st_size > 1000


# -- the command ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def done_sweep(tmp_path_factory):
    """A real sweep of mbb: one model, two loads, a LocalCluster of 2 worker processes."""
    pytest.importorskip("distributed")
    out = tmp_path_factory.mktemp("sweep")
    from io import StringIO
    from contextlib import redirect_stdout

    buf = StringIO()
    with redirect_stdout(buf):
        code = main(["sweep", "mbb", "--loads", "1,10", "--models", "linear", *TINY,
                     "--workers", "2", "--out", str(out)])
    return out, code, buf.getvalue()


def test_sweep_table_matches_the_runs(done_sweep):
    out, code, stdout = done_sweep
    assert code == 0
    assert sum(ln.startswith("[") for ln in stdout.splitlines()) == 2  # one line per run
    rows = read_csv(out / "sweep.csv")
    assert [(r["model"], float(r["load"]), r["folder"]) for r in rows] == [
        ("linear", 1.0, "linear-1e0"), ("linear", 10.0, "linear-1e1")]
    for r in rows:
        s = summary(out / r["folder"])
        assert s["load"] == float(r["load"]) and s["model"] == "linear"
        assert float(r["objective"]) == s["objective"]
        assert float(r["load_reached"]) == s["load_reached"] == float(r["load"])
        assert int(r["iterations"]) == s["iterations"] == 3
        assert r["converged"] == str(s["converged"]).lower()
        assert float(r["wall_time_s"]) == s["wall_time_s"]
        # MBB: the displacement under its load (summary.json: output_displacement_at)
        assert float(r["output_displacement"]) == s["output_displacement"] > 0
        assert r["stopped"] == "iterations"
    # linear model: the same design at every load, so compliance grows with the load squared
    c1, c10 = (float(r["objective"]) for r in rows)
    assert c10 / c1 == pytest.approx(100.0, rel=1e-9)
    assert (out / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def _stamps(out):
    return {p.parent.name + "/" + p.name: p.stat().st_mtime_ns
            for p in sorted(out.glob("*/*")) if p.name in ("summary.json", "checkpoint.npz")}


def test_sweep_again_redoes_nothing(done_sweep, capsys):
    out = done_sweep[0]
    before = _stamps(out)
    assert len(before) == 4
    assert main(["sweep", "mbb", "--loads", "1,10", *TINY, "--out", str(out)]) == 0
    assert "2 already done, 0 to run" in capsys.readouterr().out
    assert _stamps(out) == before
    assert len(read_csv(out / "sweep.csv")) == 2


def test_deleted_summary_resumes_only_that_run(done_sweep, capsys):
    out = done_sweep[0]
    old = summary(out / "linear-1e1")
    (out / "linear-1e1" / "summary.json").unlink()
    before = _stamps(out)
    assert main(["sweep", "mbb", "--loads", "1,10", *TINY, "--workers", "1",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "1 already done, 1 to run" in text and "linear-1e1 (resumed from checkpoint)" in text
    after = _stamps(out)
    assert after["linear-1e0/summary.json"] == before["linear-1e0/summary.json"]
    assert after["linear-1e0/checkpoint.npz"] == before["linear-1e0/checkpoint.npz"]
    new = summary(out / "linear-1e1")
    assert new["objective"] == pytest.approx(old["objective"], rel=1e-10)
    assert float(read_csv(out / "sweep.csv")[1]["objective"]) == new["objective"]


def test_changed_parameters_are_refused(done_sweep, capsys):
    out = done_sweep[0]
    code = main(["sweep", "mbb", "--loads", "1,10", "--nelx", "12", "--nely", "4",
                 "--iterations", "4", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "iterations = 3" in err[0]


def test_failed_and_crashed_runs_are_rows(tmp_path, monkeypatch, capsys):
    """Newton failure (exit 1) and an exception on the worker: rows, not a crash; --scheduler."""
    LocalCluster = pytest.importorskip("distributed").LocalCluster

    def fake_run_one(case_name, params, folder, resume):
        from pathlib import Path

        load = params["load"]
        if load > 50:
            raise RuntimeError("objective is not finite: nothing written")
        factor = 1.0 if load < 5 else 0.25
        _fake_summary(Path(folder), objective=load ** 2, load_reached=factor * load,
                      load_factor_reached=factor, converged=factor == 1,
                      stopped="converged" if factor == 1 else "newton")
        return {"exit_code": 0 if factor == 1 else 1, "output": ""}

    monkeypatch.setattr(sweep, "run_one", fake_run_one)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        code = main(["sweep", "mbb", "--loads", "1,10,100", "--scheduler",
                     cluster.scheduler_address, "--out", str(tmp_path)])
    assert code == 1
    text = capsys.readouterr().out
    assert "FAILED" in text and "RuntimeError" in text and "load not reached" in text
    rows = read_csv(tmp_path / "sweep.csv")
    assert [r["converged"] for r in rows] == ["true", "false", "false"]
    assert [r["stopped"] for r in rows] == ["converged", "newton", "error"]
    assert float(rows[1]["load_reached"]) == 2.5 and rows[2]["load_reached"] == ""
    assert (tmp_path / "sweep.png").is_file()


@pytest.mark.parametrize("args, field", [
    (["--loads", ""], "--loads"),
    (["--loads", "1e5,abc"], "--loads"),
    (["--loads", "1e5,-1"], "--loads"),
    ([], "--loads"),
    (["--loads", "1", "--models", "linear,rubber"], "--models"),
    (["--loads", "1", "--workers", "0"], "--workers"),
    (["--loads", "1", "--set", "volfrac=2"], "volfrac"),
])
def test_bad_input_one_line_exit_2(args, field, tmp_path, capsys):
    assert main(["sweep", "mbb", *args, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and err[0].startswith("pacto: error:")


def test_without_dask_one_line_install_hint(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["sweep", "mbb", "--loads", "1", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'pip install "pacto_ng[cluster]"' in err[0]
