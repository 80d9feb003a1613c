"""summary.json's ``leak`` (Q/(Kv P_in), the Darcy outflow through the zero-pressure
boundaries) is reported for every pressure run, not only with ``leak_max``, and pressure.png's
title quotes that same figure (it quoted another measure, the ``leakage``, before)."""
import json

import numpy as np
import pytest

pytestmark = pytest.mark.usefixtures("one_thread")

L, H = 0.02, 0.01


def _channel_case():
    """A channel L x H: inlet on the left edge, zero pressure on the right one, clamped below;
    no passive region, so a void density makes the whole channel open."""
    from pacto_ng.case import Case
    from pacto_ng.setup import Pressure, Setup
    from pacto_ng.mesh import Layout, Segment
    from pacto_ng.params import Parameters
    from pacto_ng.physics.mechanics import Supports

    defaults = Parameters(model="linear", nelx=20, nely=10, E1=1e8, E0=1e2, nu=0.3,
                          thickness=1e-3, volfrac=0.5, filter_radius=0.002, load=1e4,
                          delta_s=0.002)
    layout = Layout(L, H, segments=(Segment("inlet", (0, H), (0, 0)),
                                    Segment("zero", (L, 0), (L, H)),
                                    Segment("fixed", (0, 0), (L, 0))))
    return Case(name="leak-channel", summary="an open Darcy channel", source="this test",
                defaults=defaults, geometry=lambda p: layout,
                setup=lambda p: Setup(supports=Supports(clamp=("fixed",)),
                                      pressure=Pressure(inlet=("inlet",), zero=("zero",))),
                load_unit="Pa")


def test_an_evaluated_open_channel_reports_leak_kv_p_h_over_l(tmp_path):
    """Void everywhere: the pressure falls linearly from P_in to 0 across the channel, and
    Q/(Kv P_in) = H / L (the closed form of an open channel), without leak_max."""
    from pacto_ng.evaluate import evaluate_design

    case = _channel_case()
    np.save(tmp_path / "rho.npy", np.zeros((10, 20)))
    out = tmp_path / "ev"
    assert evaluate_design(case, case.defaults, str(tmp_path / "rho.npy"), out,
                           filtered=False, quiet=True) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["leak_max"] == 0
    assert s["leak"] == pytest.approx(H / L, rel=1e-9)


def test_a_run_without_leak_max_reports_leak_and_its_picture_quotes_it(tmp_path, monkeypatch):
    import matplotlib.axes

    from pacto_ng.cli import main

    titles = []
    set_title = matplotlib.axes.Axes.set_title

    def record(self, label, *args, **kwargs):
        titles.append(label)
        return set_title(self, label, *args, **kwargs)

    monkeypatch.setattr(matplotlib.axes.Axes, "set_title", record)
    out = tmp_path / "run"
    assert main(["run", "--no-part", "pneunet", "--maxh", "0.006", "--iterations", "2", "--out", str(out),
                 "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["leak_max"] == 0
    assert isinstance(s["leak"], float) and s["leak"] > 0
    (title,) = [t for t in titles if "p / P_in" in t]
    assert f"leak Q/(Kv P_in) = {s['leak']:.3g}" in title
    assert "leakage" not in title
