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

This file is also a case file (it defines ``CASE``): a test runs it with ``pacto run``, then
exports and analyses the two-material 3D part (:mod:`pacto_ng.post.post3d`).

The re-analysis of a two-material 3D part (:class:`~pacto_ng.post.reanalysis3d.Reanalysis3D`
with ``{material: E}``) against a closed form: a layered column, soft (E1) below and stiff (E2)
on top, each H/2 thick, meshed body-fitted (two OCC solids glued), clamped at the bottom, on
rollers on its four sides, pressure P on its top.  The state is uniaxial strain, F = diag(1,
1, s_i) in layer i, J = s_i, I1 = 2 + s_i², and the Neo-Hookean energy gives P_zz =
μ (s - 1/s) + λ ln(s)/s = -P in each layer, the same equation as the plane-strain layer of
tests/post/test_two_materials.py; the top moves by Σ (H/2)(s_i - 1).  J F⁻ᵀ N0 = N0 on the top,
so the follower pressure has the same solution, and P2 holds the piecewise linear
displacement exactly: measured 2.3e-14 relative at 1e4 and 1e5 Pa, both kinds (asserted 1e-8).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from pacto_ng import Case, Parameters, Port, Pressure, Setup, Spring, Supports
from pacto_ng.box import Block, Box, Patch
from pacto_ng.case import build_problem
from pacto_ng.core import check_gradient
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.post.part_analysis import PartAnalysis

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
    # the analysis: each remeshed tetrahedron stiff where the nodal ρ̄2 at its centroid is
    # >= 1/2, that is right of x = L/2 (the nodal ρ̄2 is linear across the plane's column,
    # 0 -> 1/2 -> 1), but near the block
    assert main(["analyse", str(out), "--kinds", "fixed", "--pressures", "1e6", "--maxh",
                 "0.02", "--order", "1"]) == 0
    printed = capsys.readouterr().out
    assert "materials (remeshed, element-wise" in printed
    data = json.loads((out / "analysis" / "analysis.json").read_text())
    mats = data["materials"]
    assert mats["mode"] == "element-wise" and mats["threshold2"] == 0.5
    assert mats["E"] == {"soft": CASE.defaults.E1, "stiff": CASE.defaults.E2}
    assert data["settings"]["E"] == mats["E"]
    assert mats["part"]["stiff"] == pytest.approx(vol[mat == 2].sum(), rel=1e-9)
    # the staircase: the remeshed volumes within 2 % of the cut part's (measured 0.4 %)
    for name in ("soft", "stiff"):
        assert mats["remeshed"][name] == pytest.approx(mats["part"][name], rel=0.02)
    assert sum(mats["remeshed"].values()) == pytest.approx(L * H * D, rel=1e-6)
    rm = pv.read(str(out / "analysis" / "remeshed.vtu"))
    rmat = np.asarray(rm.cell_data["material"])
    rE = np.asarray(rm.cell_data["E"])
    assert np.all(rE[rmat == 1] == CASE.defaults.E1) and np.all(rE[rmat == 2] == CASE.defaults.E2)
    c = np.asarray(rm.cell_centers().points)
    away = ~((c[:, 0] < 0.04 + 0.02) & (c[:, 1] > H - 0.02 - 0.02))
    assert np.array_equal(rmat[away] == 2, c[away, 0] >= L / 2)
    row = data["pressures"][0]
    assert row["fixed"]["converged"] and row["fixed"]["delta"] > 0


#: the layered column: width, height, Poisson's ratio, the soft and the stiff modulus
CW, CH, CNU, CE1, CE2 = 0.1, 0.1, 0.4, 1e6, 1e7


def _column_top(P, E_bottom, E_top):
    """-u_z of the column's top (the module docstring's closed form)."""
    from scipy.optimize import brentq

    def stretch(E):
        mu, lam = E / (2 * (1 + CNU)), E * CNU / ((1 + CNU) * (1 - 2 * CNU))
        return brentq(lambda s: mu * (s - 1 / s) + lam * np.log(s) / s + P, 0.05, 1.0,
                      xtol=1e-15, rtol=1e-15)

    return -0.5 * CH * ((stretch(E_bottom) - 1) + (stretch(E_top) - 1))


def _layered_column():
    """The body-fitted layered column of the module docstring (OCC, maxh H/3)."""
    from netgen.occ import Box as OCCBox, Glue, OCCGeometry, Pnt
    from ngsolve import Mesh

    lower = OCCBox(Pnt(0, 0, 0), Pnt(CW, CW, CH / 2))
    upper = OCCBox(Pnt(0, 0, CH / 2), Pnt(CW, CW, CH))
    lower.mat("soft")
    upper.mat("stiff")
    shape = Glue([lower, upper])
    for f in shape.faces:
        c = f.center
        f.name = ("xside" if min(c.x, CW - c.x) < 1e-9 else
                  "yside" if min(c.y, CW - c.y) < 1e-9 else
                  "bottom" if c.z < 1e-9 else "pressure" if c.z > CH - 1e-9 else "interface")
    return Mesh(OCCGeometry(shape).GenerateMesh(maxh=CH / 3))


@pytest.mark.parametrize("kind", ["fixed", "follower"])
def test_two_material_3d_reanalysis_matches_the_layered_closed_form(kind):
    mesh = _layered_column()
    assert set(mesh.GetMaterials()) == {"soft", "stiff"}
    params = Parameters(model="neohookean", E1=CE1, E2=CE2, E0=1e-3 * CE1, nu=CNU)
    ana = PartAnalysis(mesh, kind, params=params, supports=Supports(
        clamp=("bottom",), fix_x=("xside",), fix_y=("yside",)),
        ports=Port("pressure", (0.0, 0.0, -1.0)), order=2)
    sw = ana.sweep([1e4, 1e5])
    assert sw.converged.all()
    for P, delta in zip(sw.pressures, sw.delta):
        assert delta == pytest.approx(_column_top(P, CE1, CE2), rel=1e-8)
    # the check discriminates: one modulus for the whole column is far off
    assert abs(_column_top(1e5, CE1, CE1) - sw.delta[-1]) > 0.5 * sw.delta[-1]
