"""A case written as a user would (tests/cases/user_finger.py: geometry, supports, pressure,
port, material and load only) gets numerical settings derived from the case; the built-in
cases, which give theirs, resolve as before."""
import pickle
import time
from pathlib import Path

import pytest

import pacto_ng as pn
from pacto_ng.case import available_cases, load_case_file
from pacto_ng.derive import PRESSURE_DEFAULTS
from pacto_ng.cli import main
from pacto_ng.errors import InputError
from pacto_ng.params import Parameters

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

FINGER = Path(__file__).with_name("user_finger.py")
HEIGHT, LENGTH, THICKNESS, PRESSURE = 0.016, 0.08, 0.015, 1e4  # as in user_finger.py
PENALTY = ("penal_start", "penal_step", "move", "obj_tol", "iterations")  # as PRESSURE_DEFAULTS
CONTINUATION = PENALTY + ("beta_max", "beta_every", "beta_settle")


@pytest.fixture(scope="module")
def finger():
    return load_case_file(FINGER)


def test_the_user_case_resolves_with_settings_derived_from_it(finger):
    params = finger.resolve(finger.defaults)
    assert set(params.derived) == {"maxh", "filter_radius", "delta_s", *CONTINUATION}
    # 30 elements across the 16 mm height (3 significant digits)
    assert params.maxh == pytest.approx(HEIGHT / 30, rel=5e-3)
    assert params.filter_radius == pytest.approx(HEIGHT / 8, rel=5e-3)  # 1/8 of the height
    # the penalty continuation, move limit, tolerance and iteration cap of the built-in
    # pressure cases; β as theirs to twice their end, doubling early once the objective
    # settles (the 3D cases' beta_settle)
    for name in PENALTY:
        assert getattr(params, name) == getattr(PRESSURE_DEFAULTS, name), name
    assert params.beta_every == PRESSURE_DEFAULTS.beta_every
    assert params.beta_max == 2 * PRESSURE_DEFAULTS.beta_max
    assert params.beta_settle == pn.get_case("pneunet-3d").defaults.beta_settle
    assert "30 elements across 0.016 m" in params.derived["maxh"]
    # what the case gave is kept
    assert params.load == PRESSURE and params.thickness == THICKNESS
    assert params.material == "dragonskin-30"
    assert finger.resolve(params) == params  # resolved once for all


def test_the_objective_scale_is_derived_for_the_users_mechanism(finger):
    params = finger.resolve(finger.defaults)
    setup = finger.make_setup(params)
    assert setup.objective_ref == pytest.approx(0.5 / (PRESSURE * LENGTH * THICKNESS), rel=1e-4)
    assert "0.5 / (P_in L t)" in finger.derived_objective_ref(params)[1]


def test_a_given_setting_is_never_derived(finger):
    params = finger.resolve(finger.defaults.replace(maxh=0.002, beta=2.0))
    assert params.maxh == 0.002 and "maxh" not in params.derived
    assert params.filter_radius == pytest.approx(0.006)  # from the given maxh
    # a projection setting given: no projection continuation derived, its other settings at
    # their declared defaults; the penalty continuation (none given) is derived
    assert params.beta == 2.0
    assert not {"beta_max", "beta_every", "beta_settle"} & set(params.derived)
    assert params.beta_max == pn.Parameters().beta_max
    assert params.penal_start == PRESSURE_DEFAULTS.penal_start and "penal_start" in params.derived


def test_no_continuation_is_derived_where_the_case_gives_both(finger):
    given = finger.defaults.replace(penal=3.0, beta=1.0)
    params = finger.resolve(given)
    assert not set(CONTINUATION) & set(params.derived)
    for name in CONTINUATION:
        assert getattr(params, name) == getattr(pn.Parameters(), name), name


def test_changing_an_input_derives_its_dependants_again(finger):
    params = finger.resolve(finger.defaults)
    finer = params.replace(maxh=0.0004)
    assert "filter_radius" not in finer.derived
    assert finer.filter_radius == pn.Parameters().filter_radius  # back to its declared default
    assert finger.resolve(finer).filter_radius == pytest.approx(0.0012)
    assert finer.beta_max == 64.0 and "beta_max" in finer.derived  # no input of it changed


def test_a_given_filter_radius_refines_the_derived_mesh(finger):
    params = finger.resolve(finger.defaults.replace(filter_radius=0.0008))
    assert params.maxh == pytest.approx(0.0008 / 2.5, rel=5e-3)
    assert "filter radius" in params.derived["maxh"]


def test_given_and_derived_survive_pickling(finger):
    params = finger.resolve(finger.defaults)
    back = pickle.loads(pickle.dumps(params))
    assert back == params and back.derived == params.derived and back.given == params.given


def test_show_parameters_says_where_each_derived_value_came_from(capsys):
    assert main(["run", str(FINGER), "--show-parameters"]) == 0
    lines = capsys.readouterr().out.splitlines()
    maxh = next(line for line in lines if line.split()[0] == "maxh")
    assert "0.000533" in maxh and "(derived: 30 elements across 0.016 m)" in maxh
    for name in ("filter_radius", "beta_max", "penal_start"):
        assert "(derived: " in next(line for line in lines if line.split()[:1] == [name])
    load = next(line for line in lines if line.split()[:1] == ["load"])
    assert "derived" not in load
    assert any(line.split()[:1] == ["objective_ref"] and "derived" in line for line in lines)


def test_a_pressure_case_that_gives_no_drainage_depth_gets_one_element(capsys):
    """Δs follows the mesh (one element size, derive.DRAIN_ELEMENTS), not a length in
    metres that a case in other units or on another mesh would get wrong."""
    case = load_case_file(FINGER)
    params = case.resolve(case.defaults)
    assert params.delta_s == pytest.approx(params.maxh, rel=1e-3)
    assert params.derived["delta_s"] == "derived: 1 element size of 0.000533 m"
    finer = case.resolve(params.with_overrides({"maxh": "0.0004"}))
    assert finer.delta_s == 0.0004 and "delta_s" in finer.derived
    given = case.resolve(params.with_overrides({"delta_s": "0.003"}))
    assert given.delta_s == 0.003 and "delta_s" not in given.derived
    assert main(["run", str(FINGER), "--show-parameters"]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines()
                if line.split()[:1] == ["delta_s"])
    assert "0.000533" in line and "(derived: 1 element size" in line


def test_show_parameters_names_what_the_material_preset_set(capsys):
    assert main(["run", str(FINGER), "--show-parameters"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()
             if line.strip()}
    assert "(from material 'dragonskin-30': 2 μ0 (1 + ν))" in lines["E1"]
    assert "(from material 'dragonskin-30': the case's E0/E1 kept)" in lines["E0"]
    assert "(from material 'dragonskin-30': its ν)" in lines["nu"]


def test_an_E1_given_beside_a_material_preset_that_sets_another_is_refused(capsys):
    # on the command line: one line naming both, exit 2
    assert main(["run", str(FINGER), "--set", "E1=5e5", "--show-parameters"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "E1: 500000 Pa was given" in err[0] and "dragonskin-30" in err[0]
    # in a case's (or a script's) parameters
    with pytest.raises(InputError, match="E1: 3e\\+09 Pa was given, but material 'dragonskin-30'"):
        Parameters(model="wang", material="dragonskin-30", E1=3e9)
    # the preset's own value, a preset chosen over a case's E1, and ν changed under a preset
    # are no disagreement
    p = Parameters(model="wang", material="dragonskin-30")
    assert Parameters(model="wang", material="dragonskin-30", E1=p.E1).E1 == p.E1
    q = Parameters(model="wang", E1=1e5).with_overrides({"material": "dragonskin-30"})
    assert q.E1 == p.E1
    r = p.with_overrides({"nu": "0.42"})
    assert r.nu == 0.42 and r.E1 == pytest.approx(p.E1 * 1.42 / 1.45, rel=1e-12)


def test_a_short_run_of_the_user_case(tmp_path):
    t0 = time.perf_counter()
    result = pn.run(str(FINGER), out=tmp_path / "run", iterations=3, maxh=0.002)
    assert time.perf_counter() - t0 < 20
    assert len(result.history) == 3
    stored = result.summary["parameters"]
    assert stored["maxh"] == 0.002 and stored["filter_radius"] == pytest.approx(0.006)
    assert stored["beta_max"] == 64.0 and stored["iterations"] == 3


@pytest.mark.parametrize("case", available_cases(), ids=lambda c: c.name)
def test_a_built_in_case_resolves_as_before(case):
    """Built-in cases give their settings: nothing is derived but the filter radius of the two
    that leave it at 0, whose meaning (3 mesh sizes, pacto_ng.builders) it now records as a
    length, and the continuation of the three set up as a peer code and of mbb and
    cantilever-3d, which give none (derive.PENALTY, PROJECTION, CONTINUATION_OPTIMISER; the
    peer cases keep their codes' move limit); their set-ups' objective scale and their
    drainage depth are their own."""
    params = case.resolve(case.defaults)
    before = case.defaults.to_dict()  # the resolution before derivations: order only
    if not before["order"] and before["model"] != "auto":
        before["order"] = case.order_for(before["model"])
    changed = {k for k, v in params.to_dict().items() if before[k] != v}
    expected = {"filter_radius"} if case.name in ("cantilever", "inverter") else set()
    if case.name in ("sorotop", "topress", "topress-3d"):
        expected = {"penal_start", "penal_step", "beta_max", "beta_every", "beta_settle",
                    "iterations", "obj_tol"}
    if case.name in ("mbb", "cantilever-3d"):
        expected = {"penal_start", "penal_step", "beta_max", "beta_every", "beta_settle",
                    "iterations", "obj_tol", "move"}
    assert changed == expected and set(params.derived) == expected
    if "filter_radius" in expected:
        assert params.filter_radius == pytest.approx(3.0 * params.maxh, rel=1e-12)
    if not case.analysis_only:
        assert case.make_setup(params).objective_ref == case.setup(params).objective_ref


@pytest.mark.slow
def test_the_user_case_at_its_derived_defaults_gives_a_working_part(tmp_path):
    result = pn.run(str(FINGER), out=tmp_path / "full")
    s = result.summary
    assert s["greyness"] <= 0.02
    assert s["sealed"] is True
    assert abs(s["part"]["gap"]) <= 0.2
