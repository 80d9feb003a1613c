"""The Darcy outflow through the zero-pressure boundaries (``leak_max``,
:class:`pacto_ng.physics.darcy_leakage.Outflow`) against closed forms, and its gradient
through the whole chain against central differences."""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng.mesh import Layout, Segment, structured_mesh
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_leakage import Outflow

pytestmark = pytest.mark.usefixtures("one_thread")

L, H = 0.02, 0.01


def _channel(wall=None, order=1):
    """40 x 20 quads on L x H, inlet (P_in = 1e6) on the left edge, zero pressure on the right
    one, no flow through the others; ρ̄ = 1 on x in ``wall`` (a pair), 0 elsewhere."""
    mesh = structured_mesh(Layout(L, H, segments=(Segment("inlet", (0, H), (0, 0)),
                                                  Segment("zero", (L, 0), (L, H)))), 40, 20)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e6, order=order)
    x = np.array([np.mean([mesh[v].point[0] for v in el.vertices]) for el in mesh.Elements()])
    rho = np.zeros(mesh.ne) if wall is None else ((x > wall[0]) & (x < wall[1])).astype(float)
    p = dar.forward(rho)
    return dar, rho, p


@pytest.mark.parametrize("order", [1, 2])
def test_an_open_channel_passes_kv_p_h_over_l(order):
    """Void everywhere (K = Kv, no drainage): the pressure falls linearly from P_in to 0 and
    the flow through the channel is Kv P_in H / L, exactly in the discrete solution."""
    dar, rho, p = _channel(order=order)
    q = Outflow(dar).forward(rho, p)
    print("open channel: Q/(Kv P_in) =", q, "closed form", H / L)
    assert q == pytest.approx(H / L, rel=1e-10)


def test_a_3d_channel_leaks_its_cross_section_over_length_and_the_smallest_side():
    """3D: void everywhere in a box L x H x W (x 0 -> 0.02 the inlet at x = 0, zero pressure
    at x = L): Q = Kv P_in H W / L, reported per unit of the smallest side W, H W / (L W) =
    H / L, the 2D channel's figure (one limit serves both)."""
    from ngsolve.meshes import MakeStructured3DMesh

    W = 0.005
    mesh = MakeStructured3DMesh(hexes=True, nx=8, ny=4, nz=2,
                                mapping=lambda x, y, z: (L * x, H * y, W * z))
    dar = DarcyPressure(mesh, inlet="back", zero="front", p_in=1e6)
    rho = np.zeros(mesh.ne)
    q = Outflow(dar).forward(rho, dar.forward(rho))
    assert q == pytest.approx(H * W / (L * W), rel=1e-10)


def test_a_solid_wall_lets_almost_nothing_through():
    """A solid wall two penetration depths thick (x in [0.006, 0.010]) between inlet and
    outlet: the drainage takes the inflow and the flow out falls to the solid's flow
    coefficient's scale (Ks = 1e-7 Kv), 6 orders of magnitude below the open channel."""
    dar, rho, p = _channel(wall=(0.006, 0.010))
    q = Outflow(dar).forward(rho, p)
    print("sealed: Q/(Kv P_in) =", q)
    assert 0 <= q < 1e-6 * H / L


# -- the gradient through the chain (the small pa-inverter of test_follower_gradients) ---------
def _case():
    from pacto_ng.case import Case
    from pacto_ng.setup import Pressure, Setup
    from pacto_ng.params import Parameters
    from pacto_ng.physics.loads import Port, Spring
    from pacto_ng.physics.mechanics import Supports
    from small_cases import small_pa_layout

    defaults = Parameters(model="linear", nelx=20, nely=10, E1=3e8, E0=3e3, nu=0.4,
                          thickness=1e-3, volfrac=0.4, filter_radius=0.002, beta=2.0,
                          load=2e5, k_out=1e4, delta_s=0.002, newton_rtol=1e-12,
                          leak_max=0.01)
    setup = lambda p: Setup(  # noqa: E731
        supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
        springs=(Spring("output", p.k_out, (1.0, 0.0)),), port=Port("output", (-1.0, 0.0)),
        solid=("block",), objective="mechanism",
        pressure=Pressure(inlet=("inlet",), zero=("zero",)))
    return Case(name="outflow-test", summary="small pa-inverter", source="this test",
                defaults=defaults, geometry=lambda p: small_pa_layout(), setup=setup,
                load_unit="Pa")


@pytest.mark.parametrize("model,robust", [("linear", 0), ("wang", 0), ("wang", 2)])
def test_leak_constraint_gradient(model, robust):
    """``--set leak_max``: the outflow and its constraint (of every realisation that carries the
    set-up's constraints) against central differences, the pressure's adjoint included."""
    from small_cases import chain_fd

    from pacto_ng.case import build_problem

    case = _case()
    problem = build_problem(case, case.defaults.replace(model=model, robust=robust))
    limits = [c for c in problem.constraints if c.startswith("leak_limit")]
    assert limits == (["leak_limit_e"] if robust == 2 else ["leak_limit"])
    x0 = np.random.default_rng(4).uniform(0.3, 0.7, problem.field.n)
    values = problem.chain.forward(x=x0)
    assert values["leak"] > 0
    for name in limits + [n for n in problem.reports if n.startswith("leak")]:
        err = chain_fd(problem.chain, name, x0, h=1e-5, directions=3).rel_error
        print(model, robust, name, err)
        assert err < 1e-6, (name, err)


def test_leak_max_needs_a_pressure_load():
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.params import InputError

    case = get_case("cantilever")
    with pytest.raises(InputError, match="leak_max: case 'cantilever' has no pressure load"):
        build_problem(case, case.parameters({"leak_max": 0.01, "maxh": 0.02}))


def test_a_run_reports_its_leak(tmp_path):
    """``pacto run ... --set leak_max``: history.csv has the ``leak`` column and summary.json the
    final design's ``leak``."""
    import csv
    import json

    from pacto_ng.cli import main

    out = tmp_path / "run"
    assert main(["run", "--no-part", "pneunet", "--maxh", "0.006", "--iterations", "3", "--set",
                 "leak_max=0.01", "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(open(out / "history.csv")))
    assert len(rows) == 3 and all(float(r["leak"]) > 0 for r in rows)
    summ = json.loads((out / "summary.json").read_text())
    assert summ["leak"] > 0 and summ["parameters"]["leak_max"] == 0.01
