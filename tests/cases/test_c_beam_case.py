"""`pacto run c-beam`: the analysis case reports the largest load factor per model and a
deformed-mesh picture; the Wang model carries at least 6x the Neo-Hookean load (thesis
Table 5.2 ratio)."""
import json

from pacto_ng.cli import main


def test_c_beam_neohookean_vs_wang(tmp_path):
    res = {}
    for model in ("neohookean", "wang"):
        out = tmp_path / model
        assert main(["run", "c-beam", "--model", model, "--out", str(out), "--quiet"]) == 0
        s = json.loads((out / "summary.json").read_text())
        assert (out / "deformed.png").stat().st_size > 10_000
        res[model] = s
    nh, wang = res["neohookean"], res["wang"]
    assert not nh["reached_requested_maximum"] and "inverted" in nh["stopped_because"]
    assert wang["load_factor_reached"] >= 6.0 * nh["load_factor_reached"]
    f1, f2 = nh["forces_reached_N"]
    assert abs(f2 / f1 - 1.5) < 1e-12  # the load ratio is kept
