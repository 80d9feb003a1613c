"""The gallery page (benchmarks/gallery.py) built from fake run folders: the figures on the page
are the ones in each folder's summary.json and gallery record, a failed or missing run is said
so, and the picture is one small PNG per case."""
import json

from PIL import Image

from benchmarks import gallery


def _write(folder, name, data):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(json.dumps(data))


def _fake_runs(runs):
    """pa-inverter: a finished run with a part; pneunet: a run that failed; mbb: none."""
    done = runs / "pa-inverter"
    _write(done, "summary.json", {
        "case": "pa-inverter", "model": "neohookean", "load": 2.5e5, "load_unit": "Pa",
        "iterations": 87, "objective": -0.0123456, "objective_name": "worst_case",
        "output_displacement": 0.00043219, "volume_fraction": 0.2049, "greyness": 0.04217,
        "converged": False, "stopped": "iterations",
        "message": "stopped at the iteration cap (87)", "wall_time_s": 7.4,
        "load_factor_reached": 1.0, "mesh": {"elements": 2906, "dim": 2},
        "part": {"made": True, "sealed": False, "gap": 0.0351, "wall_time_s": 1.3},
        "sealed": False})
    _write(done, gallery.RECORD, {
        "command": f"pacto run pa-inverter --out {done}", "started": "2026-01-02 03:04 UTC",
        "threads": 1, "cores": 2, "load_average": 1.23, "machine": "2 cores (test CPU)",
        "timeout_s": 1800.0, "timed_out": False, "exit_code": 0, "wall_s": 9.6,
        "last_lines": []})
    _write(done / "refine", "summary.json", {
        "status": "steps", "delta_before": 0.00041, "delta_after": 0.00052, "gain": 0.2683,
        "gap": 0.2019, "sealed": True, "units": {"delta": "m"}, "wall_time_s": 21.7})
    Image.new("RGB", (300, 120), "white").save(done / "design.png")
    part = Image.new("RGB", (150, 100), "white")
    part.paste((40, 120, 200), (50, 25, 100, 75))
    part.save(done / "part.png")
    _write(runs / "pneunet", gallery.RECORD, {
        "command": "pacto run pneunet", "started": "2026-01-02 03:05 UTC", "threads": 1,
        "cores": 2, "load_average": 1.0, "machine": "2 cores (test CPU)", "timeout_s": 60.0,
        "timed_out": False, "exit_code": 1, "wall_s": 3.2,
        "last_lines": ["pacto: error: the Newton solver failed at iteration 3"]})


def test_page_figures_are_the_summary_figures(tmp_path):
    runs, out, img = tmp_path / "runs", tmp_path / "docs" / "gallery.md", tmp_path / "img"
    _fake_runs(runs)
    text = gallery.build(str(runs), ["pa-inverter", "pneunet", "mbb"], str(out), str(img),
                         "PACTO_THREADS=1 python -m benchmarks.gallery --runs R --run")
    assert out.read_text() == text
    row = next(ln for ln in text.splitlines() if ln.startswith("| [pa-inverter]"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:] == ["2D, 2,906 elements", "neohookean, 2.5e+05 Pa", "worst_case -0.01235",
                         "0.0004322", "87", "no", "0.042", "**no**", "+3.5 %", "7.4", "9.6"]
    entry = text.split("### pa-inverter")[1].split("###")[0]
    assert gallery.builtin_cases()["pa-inverter"] in entry  # the case's one-line description
    for said in ("stopped at the iteration cap (87)", "volume fraction: 0.205",
                 "1.3 s part", "22 s refinement", "9.6 s the whole `pacto run`",
                 "load average 1.2 at its start", "1 thread",
                 "Δ 0.00041 → 0.00052 m (+26.8 %), +20.2 % from the design's Δ"):
        assert said in entry, said
    assert "2 cores (test CPU)" in text and "PACTO_THREADS=1 python -m benchmarks" in text
    failed = text.split("### pneunet")[1].split("###")[0]
    assert "exit code 1" in failed and "the Newton solver failed at iteration 3" in failed
    assert "not run: no summary.json" in text.split("### mbb")[1]
    pic = img / "pa-inverter.png"
    assert "![pa-inverter: design.png (left) and part.png](../img/pa-inverter.png)" in text
    assert pic.stat().st_size < gallery.IMG_BYTES
    with Image.open(pic) as im:
        assert im.size == (250 + gallery.GAP + 150, 100)  # side by side at the part's height
    assert not (img / "pneunet.png").exists() and not (img / "mbb.png").exists()
