"""The built-in cases give the results they gave before they were rewritten on the public case
API: the objective history of a few iterations, pinned from the code of commit ed63e52 (before
the rewrite), equal to 1e-8 relative.  They run with that commit's optimiser, MMA throughout
(``--optimizer mma``; the default now switches to GCMMA on the final problem), and at the full
load from the first iteration, as then (``load_ramp=0`` where the load ramp chosen from the
load would start lower: the Neo-Hookean cantilever), and with the standard chain (the
pa-inverter's default is now the robust formulation: ``robust=0``; the MBB beam's is now the
library's penalty and projection continuation: ``TOP88_OPTIMISER``)."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main
from top88_reference import TOP88_OPTIMISER

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

#: key: (pacto run options, elements, objective history of commit ed63e52)
PINS = {
    'mbb': (['--optimizer', 'mma', '--iterations', '3', *TOP88_OPTIMISER], 1200, [1007.0221007367791, 671.4110628090416, 464.7119626284639]),
    'cantilever': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '0.04'], 350, [123551.87220656009, 95021.68990908479, 78862.4071909315]),
    'cantilever-nh': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '0.04', '--model', 'neohookean', '--load', '1e5', '--set', 'load_ramp=0'], 350, [45389.21477701899, 36912.17748395768, 31534.172466164506]),
    'inverter': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '6e-6'], 713, [4.534562362228096e-06, 4.358170708555088e-08, -2.2283984149247137e-10]),
    'pa-inverter': (['--optimizer', 'mma', '--iterations', '3', '--set', 'robust=0'], 2906, [0.01337275426729399, 0.0074730269523619825, 0.00213775887745167]),
    'pa-inverter-q': (['--optimizer', 'mma', '--iterations', '3', '--nelx', '40', '--nely', '20', '--set', 'robust=0'], 800, [0.012957819504872452, 0.007121026795462842, 0.00196499410436575]),
    'pa-gripper': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '0.008'], 724, [0.0005747582995325501, 0.0002339342210054681, -0.00010413370677123887]),
    'pneunet': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '0.005'], 426, [-0.0003455358780458029, -0.002799083689627762, -0.005431458387779405]),
    'pneunet-wang': (['--optimizer', 'mma', '--iterations', '2', '--maxh', '0.005', '--model', 'wang', '--set', 'load_type=follower'], 426, [-0.0012073536097380617, -0.003858461439077257]),
    'mm-gripper': (['--optimizer', 'mma', '--iterations', '3', '--maxh', '0.008', '--set', 'move=0.05'], 724, [0.0002417488140028292, 0.0001758155198488438, 8.933018139565972e-05]),
}


@pytest.mark.parametrize("key", sorted(PINS))
def test_objective_history_as_before_the_rewrite(key, tmp_path):
    args, elements, history = PINS[key]
    case = key.removesuffix("-q").removesuffix("-nh").removesuffix("-wang")
    assert main(["run", "--no-part", case, *args, "--out", str(tmp_path), "--quiet"]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["mesh"]["elements"] == elements
    got = np.array(s["objective_history"])
    ref = np.array(history)
    # relative to the history's scale: the inverter's third value (-2e-10) is 2e4x below it
    assert np.max(np.abs(got - ref)) <= 1e-8 * np.max(np.abs(ref))


def test_c_beam_as_before_the_rewrite(tmp_path):
    assert main(["run", "--no-part", "c-beam", "--model", "wang", "--out", str(tmp_path), "--quiet"]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["load_factor_reached"] == 20.0
    tips = np.array(s["tip_displacements"]["f1"] + s["tip_displacements"]["f2"])
    ref = np.array([-6.851523081059582, -9.545056209502382, 0.6875631633058272, 0.5619990977642123])
    assert np.max(np.abs(tips - ref)) <= 1e-8 * np.max(np.abs(ref))
