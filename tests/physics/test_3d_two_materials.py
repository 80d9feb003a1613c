"""Adjoint gradients of the two-material chain in 3D against central finite differences.

The chain a run builds for a two-material case (mm-gripper's, :mod:`pacto_ng.builders`: two
stacked design fields, each embedded, Helmholtz-filtered, projected (β = 2) and fixed on the
passive solid, ρ̄1 the solid/void density, ρ̄2 the soft (0) / stiff (1) one; the two-material
SIMP modulus ``E = (1-ρ̄1^p) E0 + ρ̄1^p [(1-ρ̄2^p) E1 + ρ̄2^p E2]``; the Darcy pressure driven
by ρ̄1; the mechanism objective -Δ/SE with an output spring; the volume constraints on ρ̄1 and
on ρ̄2 (``volfrac2``)), built by :func:`~pacto_ng.case.build_problem` from a small
:class:`~pacto_ng.box.Box` case meshed as Netgen tetrahedra and as structured hexahedra, for
the linear and the Neo-Hookean model, with the Darcy pressure as a fixed body load and as a
follower load (as mm-gripper's: ``--set load_type=follower``).

The reference is :func:`pacto_ng.core.check_gradient` with the five-point stencil at h = 1e-4
and the tolerance 1e-6 of test_3d_gradients.py, Newton to 1e-12 of the load, along random
directions of each design field separately (so that an error in either field's sensitivity
shows), drawn again where ``Σ|g_i d_i| / |g·d|`` exceeds 100, as ``pacto check-gradients``
does (pacto_ng/gradcheck.py): along such a direction the finite difference measures its own
noise, not the gradient.  The perturbed designs are analysed once for all the responses.  The
load gives an output displacement of 4.9 - 5.2 % of the length (asserted > 2 %), so that
Neo-Hookean is away from its linear limit.  Measured worst relative errors (2026-12-03): the
objective 2.9e-8 (tetrahedra, Neo-Hookean, follower load, along the stiff field), most others
1e-12 - 1e-8; the volumes 2e-11.  By default: both meshes with the fixed load, both models,
and the Neo-Hookean follower load on the tetrahedra; under ``-m slow`` the follower load on
the hexahedra (Neo-Hookean 5 - 8 s) and the linear material under the follower load (solved
by Newton in 3D; 4 - 5 s each).  The file by default: 15 s (2026-12-03, with another
engineer's jobs on the second core).

This file is also a case file (it defines ``CASE``): the last test runs it with ``pacto run``
and exports the two-material 3D part (:mod:`pacto_ng.post.post3d`).
"""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng import Case, Parameters, Port, Pressure, Setup, Spring, Supports
from pacto_ng.box import Block, Box, Patch
from pacto_ng.case import build_problem
from pacto_ng.core import check_gradient
from pacto_ng.physics.darcy import DarcyPressure

pytestmark = pytest.mark.usefixtures("one_thread", "pacto_one_thread")

L, H, D = 0.24, 0.12, 0.06
TOL = 1e-6


def _geometry(p: Parameters) -> Box:
    """The box clamped at x = 0, the pressure inlet its face y = 0 and zero pressure on its
    face y = H, the output strip y < H/4 of the face x = L, a passive solid block at the
    clamp's upper corner (grid-aligned for the 0.02 m hexahedra)."""
    return Box(L, H, D,
               patches=(Patch("fixed", "xmin"), Patch("output", "xmax", (0.0, 0.0), (H / 4, D)),
                        Patch("inlet", "ymin"), Patch("zero_pressure", "ymax")),
               blocks=(Block("block", "solid", (0.0, H - 0.02, 0.0), (0.04, H, D)),))


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("fixed",)),
                 springs=(Spring("output", 2e5, (0.0, 1.0, 0.0)),),
                 port=Port("output", (0.0, 1.0, 0.0)), solid=("block",), objective="mechanism",
                 pressure=Pressure(inlet=("inlet",), zero=("zero_pressure",)), materials=2)


CASE = Case(
    name="two-materials-3d",
    summary="a small two-material pressure-actuated box (3D), minimise -Δ/SE",
    source="tests: mm-gripper's chain on a box",
    # mm-gripper's materials (E1 soft, E2 = 10 E1 stiff, E0 = 1e-6 E1, ν = 0.4)
    defaults=Parameters(model="linear", maxh=0.03, E1=3e8, E2=3e9, E0=3e2, nu=0.4, volfrac=0.3,
                        volfrac2=0.15, filter_radius=0.04, beta=2.0, penal=3.0, load=1e6,
                        delta_s=0.02, newton_rtol=1e-12, order=1),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)


def problem_of(kind, model, load):
    """The built problem on tetrahedra (maxh 0.03) or 12 x 6 x 3 hexahedra (0.02 m)."""
    params = CASE.defaults.replace(model=model, load_type=load)
    if kind == "hex":
        params = params.replace(nelx=12, nely=6, nelz=3)
    return build_problem(CASE, params)


def field_errors(problem, x0, names, h=1e-4, directions=1):
    """``{(name, field): worst relative error}`` of the adjoint gradient of each value in
    ``names`` along random directions of design field 1 and of field 2 (the other fixed).  A
    value whose adjoint gradient with respect to a field is exactly zero (the volume of one
    field with respect to the other) is not in the dict; its central differences along those
    directions are asserted to vanish (below 1e-9 of its gradient's size on the other
    field)."""
    chain, n = problem.chain, problem.n_design
    chain.forward(x=x0)
    grads = {name: np.asarray(chain.gradient(name)).copy() for name in names}
    analysed = {}

    def value(x, name):
        key = x.tobytes()
        if key not in analysed:
            out = chain.forward(x=x)
            analysed[key] = {nm: float(out[nm]) for nm in names}
        return analysed[key][name]

    errors = {}
    for i in (0, 1):
        part = slice(i * n, (i + 1) * n)

        def whole(xi, part=part):
            x = x0.copy()
            x[part] = xi
            return x

        for name in names:
            res = check_gradient(lambda xi, nm=name: value(whole(xi), nm),
                                 lambda xi, nm=name, part=part: grads[nm][part], x0[part], h=h,
                                 directions=directions, seed=i, stencil=4,
                                 max_cancellation=100.0)
            if np.any(grads[name][part]):
                errors[(name, i + 1)] = res.rel_error
            else:
                size = np.abs(grads[name]).sum()
                assert size > 0 and np.max(np.abs(res.numeric)) < 1e-9 * size, (name, i + 1)
    return errors


def check_two_materials(kind, model, load):
    problem = problem_of(kind, model, load)
    assert problem.n_design_fields == 2 and problem.mesh.dim == 3
    assert problem.constraints == ["volume", "volume2"]
    mech = problem.mech
    assert mech.linear == (model == "linear" and load == "fixed")
    x0 = np.random.default_rng(2).uniform(0.3, 0.7, 2 * problem.n_design)
    vals = problem.chain.forward(x=x0)
    print(kind, problem.mesh.ne, model, load, "Δ / L", float(vals["delta"]) / L,
          "Newton iterations", mech.result.iterations)
    assert float(vals["delta"]) / L > 0.02
    if model == "neohookean":
        assert mech.result.iterations > 1  # really nonlinear
    # the passive block is solid and stiff in both fields
    block = problem.field.solid
    assert block.any()
    assert np.all(np.asarray(vals["rho_bar1"])[block] == 1.0)
    assert np.all(np.asarray(vals["rho_bar2"])[block] == 1.0)
    errors = field_errors(problem, x0, [problem.objective] + problem.constraints)
    print(errors)
    assert max(errors.values()) < TOL, errors
    # the stiff field moves the objective: its gradient is not negligible beside the first's
    problem.chain.forward(x=x0)
    g = np.asarray(problem.chain.gradient(problem.objective))
    n = problem.n_design
    assert np.linalg.norm(g[n:]) > 0.05 * np.linalg.norm(g[:n])
    # the pressure sees the solid/void field only
    dar = next(b for b in problem.chain.blocks if isinstance(b, DarcyPressure))
    assert dar.inputs[0] == "rho_bar1"


@pytest.mark.parametrize("kind, model, load", [
    ("tet", "linear", "fixed"), ("tet", "neohookean", "fixed"), ("tet", "neohookean", "follower"),
    ("hex", "linear", "fixed"), ("hex", "neohookean", "fixed"),
    pytest.param("hex", "neohookean", "follower", marks=pytest.mark.slow),
    pytest.param("tet", "linear", "follower", marks=pytest.mark.slow),
    pytest.param("hex", "linear", "follower", marks=pytest.mark.slow)])
def test_two_material_chain_gradients_3d(kind, model, load):
    check_two_materials(kind, model, load)


def test_export_of_a_two_material_3d_part(tmp_path, capsys):
    """``pacto export`` of a 3D two-material run, on a design chosen so that the parts are
    known: solid everywhere (ρ̄1 = 1), the stiff material in the half x > L/2 (ρ̄2 = 0 or 1,
    no filter), on 12 x 6 x 3 hexahedra whose vertex plane x = L/2 then has the nodal
    ρ̄2 = 1/2 exactly.  The STL is the whole box; the VTU's cells are stiff (E2) right of
    that plane and soft (E1) left of it, but near the passive solid block (of the stiff
    material), and the materials fill the part; ``analyse`` refuses the design in one
    line."""
    import pyvista as pv

    from pacto_ng.cli import main
    from pacto_ng.post.grid import cell_volumes
    from small_cases import run_with_design

    out = run_with_design(
        tmp_path / "run", [__file__, "--nelx", "12", "--nely", "6", "--nelz", "3", "--set",
                           "filter=none", "--iterations", "1"],
        lambda c: np.r_[np.ones(len(c)), (c[:, 0] > L / 2).astype(float)])
    assert main(["export", str(out), "--format", "vtu", "--out", str(tmp_path / "p.vtu")]) == 0
    printed = capsys.readouterr().out
    assert "materials soft" in printed and "(ρ̄2 at 0.5)" in printed
    solid = pv.read(str(tmp_path / "p.vtu"))
    vol = cell_volumes(solid)
    assert vol.sum() == pytest.approx(L * H * D, rel=1e-9)  # ρ̄1 = 1: the whole box
    mat = np.asarray(solid.cell_data["material"])
    assert set(np.unique(mat)) == {1, 2}
    assert np.all(np.asarray(solid.cell_data["material_soft"]) == (mat == 1))
    assert np.all(np.asarray(solid.cell_data["material_stiff"]) == (mat == 2))
    E = np.asarray(solid.cell_data["E"])
    assert np.all(E[mat == 1] == CASE.defaults.E1) and np.all(E[mat == 2] == CASE.defaults.E2)
    x = np.asarray(solid.cell_centers().points)
    right = x[:, 0] > L / 2
    near_block = (x[:, 0] < 0.04 + 0.02) & (x[:, 1] > H - 0.02 - 0.02)
    assert np.all(mat[right] == 2)
    # left of the plane, away from the block, soft but for slivers of the cut at the vertices
    # exactly at ρ̄2 = 1/2 (counted stiff, 1e-9 above: measured 1.6e-14 m³ each)
    assert vol[~right & ~near_block & (mat == 2)].sum() < 1e-9 * L * H * D
    assert vol[right].sum() == pytest.approx(L / 2 * H * D, rel=1e-6)
    # the passive block is of the stiff material (ρ̄2 = 1), but where its vertices are shared
    # with soft elements the nodal ρ̄2 is below 1/2 (the rule of the 2D part): partly stiff
    inside_block = (x[:, 0] < 0.04) & (x[:, 1] > H - 0.02)
    assert 0 < vol[inside_block & (mat == 2)].sum() < 0.04 * 0.02 * D
    assert np.all(np.asarray(solid.cell_data["rho_bar1"]) == 1.0)
    assert {"rho_bar2", "u", "p", "strain", "stress"} <= set(solid.array_names)
    assert main(["export", str(out), "--format", "stl", "--units", "m"]) == 0
    stl = pv.read(str(out / "export" / "design.stl"))
    assert stl.n_open_edges == 0 and stl.is_manifold
    assert abs(stl.volume) == pytest.approx(L * H * D, rel=1e-6)
    capsys.readouterr()
    assert main(["analyse", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("pacto: error: the analysis of a two-material design is not supported for "
                   "3D runs yet")
