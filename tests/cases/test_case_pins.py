"""Every built-in case whose results no other test pins gives the results it gave when they
were pinned: the element count and the objective history of a 3-iteration run at a coarse
mesh, equal to 1e-8 relative (the cases pinned elsewhere: mbb against the 88-line code,
tests/unit/test_q4_mbb.py; sorotop, topress and topress-3d against Kumar's codes,
tests/cases/test_peer_setups.py and test_topress_3d.py; cantilever, inverter, pa-inverter,
pa-gripper, pneunet and mm-gripper, tests/cases/test_rewrite_pins.py; c-beam,
tests/cases/test_c_beam_case.py).

These are regression pins, not references: the values are what the code gave at commit
921b122 (2026-12-06, 1 NGSolve thread), with each case's defaults at that commit (the
continuation, the robust formulation of jaw-gripper and pa-gripper-3d, Wang's law of the
silicone cases).  A change of a case's defaults or of the chain that moves one of them is a
change of that case's results: re-pin it in the same commit and say why in its message."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

#: case: (pacto run options, elements, objective history at commit 921b122)
PINS = {
    "soft-finger": (["--maxh", "0.006"], 157,
                    [-0.003941147565942031, -0.004971664712525881, -0.006008590833631448]),
    "jaw-gripper": (["--maxh", "0.01"], 416,
                    [0.0008529685061930102, -0.00116881498967955, -0.0031653162820252305]),
    "pneunet-silicone": ([], 2400,
                         [0.018748387827703338, -0.006690990672566824, -0.02273645965103394]),
    # re-pinned 2026-12-07: its spring and port moved from the pad's corner to its edge
    "gripper-silicone": ([], 5000,
                         [0.013277450218924442, 0.0017155409674469752, -0.0019030944109398134]),
    "cantilever-3d": (["--maxh", "0.06"], 830,
                      [21092.548070475917, 19204.125532889175, 18103.326322556728]),
    "pneunet-3d": (["--maxh", "0.006"], 2081,
                   [0.00033171693320546773, 0.00016181995878912083, -0.00011488504907605078]),
    "pa-inverter-3d": (["--maxh", "0.008"], 2551,
                       [0.000858885194649504, 0.0006870052856567462, 0.0004041057549895976]),
    "pa-gripper-3d": (["--maxh", "0.008"], 2643,
                      [0.00010890320738030523, -9.917140511871439e-06, -9.25848202523054e-05]),
}


#: the pins of 9-13 s each, under ``pytest -m slow`` (the suite's 10 minutes)
SLOW = ("gripper-silicone", "pa-gripper-3d", "pa-inverter-3d")


@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.slow) if c in SLOW else c
                                  for c in sorted(PINS)])
def test_the_case_gives_its_pinned_objective_history(case, tmp_path):
    args, elements, history = PINS[case]
    assert main(["run", "--no-part", case, *args, "--iterations", "3", "--out", str(tmp_path),
                 "--quiet"]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["mesh"]["elements"] == elements
    got, ref = np.array(s["objective_history"]), np.array(history)
    # relative to the history's scale: a value may pass through zero
    assert np.max(np.abs(got - ref)) <= 1e-8 * np.max(np.abs(ref))
