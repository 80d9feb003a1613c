"""Two-material post-analysis (post.materials): the part keeps a soft (E1) and a stiff (E2)
region, and the re-analysis uses each region's modulus.

Closed form: a layered block in plane strain, soft layer (E1) below, stiff layer (E2) on top,
each H/2 thick, clamped at the bottom, rollers on both sides (u_x = 0), pressure P on the top.
The state is uniaxial strain, F = diag(1, s_i) in layer i, and the Neo-Hookean energy
φ = μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)² (I1 = 1 + s² + 1, J = s) gives the first
Piola–Kirchhoff stress P_yy = μ (s - 1/s) + λ ln(s)/s = -P in each layer; the top moves by
u_y = Σ (H/2)(s_i - 1).  For this state J F⁻ᵀ N0 = N0 on the top, so the follower pressure has
the same solution.  The displacement is piecewise linear in y with its kink on the interface:
on a body-fitted two-region mesh the P2 solution is exact, and the analysis matches the closed
form to Newton's tolerance (measured: 3.2e-10 relative at 1e4 and 1e5 Pa, both kinds; asserted
1e-8).  A mesh whose elements straddled the interface, or one modulus for the whole part, would
not (at 1e5 Pa the closed form with E1 throughout is 4.43e-3 m against 2.44e-3 m; the
small-strain two-material answer 2.57e-3 m, 5 % off: the check sees the Neo-Hookean model).

End to end: a short mm-gripper run on a coarse mesh (20 iterations, maxh 0.008), `pacto
analyse` at two pressures (the run's own linear law, each region its modulus) and `pacto
export` as stl, vtk and msh; both materials are in the part and Δ is read back from
remeshed.vtu at the case's output point.
"""
import json

import numpy as np
import pytest
from scipy.optimize import brentq

from pacto_ng.cli import main
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

W, H, NU, T = 0.1, 0.1, 0.4, 1e-3
E1, E2 = 1e6, 1e7
PRESSURES = [1e4, 1e5]


def _cross(a, b):
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def _stretch(E, P):
    """s with μ (s - 1/s) + λ ln(s)/s = -P (uniaxial plane strain, Neo-Hookean)."""
    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    return brentq(lambda s: mu * (s - 1 / s) + lam * np.log(s) / s + P, 0.05, 1.0, xtol=1e-15,
                  rtol=1e-15)


def layered_top_displacement(P, E_bottom, E_top):
    return 0.5 * H * (_stretch(E_bottom, P) - 1) + 0.5 * H * (_stretch(E_top, P) - 1)


def _layered_design():
    from netgen.meshing import Element0D
    from ngsolve import Mesh
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(quads=True, nx=8, ny=8, mapping=lambda x, y: (W * x, H * y))
    ngm = mesh.ngmesh
    corner = int(np.argmin(np.hypot(*(np.asarray(ngm.Coordinates()) - [0.0, H]).T)))
    ngm.Add(Element0D(corner + 1, index=ngm.AddRegion("output", dim=0)))
    mesh = Mesh(ngm)
    cen = np.array([np.mean([mesh[v].point for v in el.vertices], axis=0)
                    for el in mesh.Elements()])
    return mesh, (cen[:, 1] > 0.5 * H).astype(float)


class Analysed:
    """The layered block's part and its sweeps (what ``pacto analyse`` makes of a design)."""

    def __init__(self, remeshed, sweeps):
        self.remeshed, self.sweeps = remeshed, sweeps


def _analysed(mesh, rho2, out, kinds):
    """The layered design's part (ρ̄1 = 1, ρ̄2 thresholded at 0.5; the top wetted), its
    Neo-Hookean sweeps (E1 soft, E2 stiff, each region its own: PartAnalysis), and the files
    a part's analysis writes of its regions: remeshed.vtu and materials.png."""
    from pacto_ng.params import Parameters
    from pacto_ng.post.export import write_vtu
    from pacto_ng.post.pictures import plot_materials
    from pacto_ng.post.materials import stiff_region
    from pacto_ng.post.part_analysis import PartAnalysis
    from pacto_ng.post.remesh import remesh
    from pacto_ng.post.threshold import threshold

    rm = remesh(threshold(mesh, np.ones(mesh.ne)), H / 6, clamp=("bottom",),
                wet_boundaries=("top",), stiff=stiff_region(mesh, rho2, 0.5))
    params = Parameters(model="neohookean", E1=E1, E2=E2, E0=1e-3 * E1, nu=NU, thickness=T,
                        plane="strain")
    sweeps = {kind: PartAnalysis(rm.mesh, kind, params=params, order=2,
                                 ports=Port("output", (0.0, -1.0)),
                                 supports=Supports(clamp=("bottom",), fix_x=("left", "right")))
              .sweep(PRESSURES) for kind in kinds}
    sw = sweeps[kinds[-1]]
    write_vtu(out / "remeshed.vtu", rm.mesh, sw.displacement(),
              phi=sw.analysis.energy_density, E={"soft": E1, "stiff": E2})
    plot_materials(out / "materials.png", rm.mesh, mirror=False)
    return Analysed(rm, sweeps)


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    """The layered block's design on a structured quad mesh (the interface y = H/2 on element
    edges, where the nodal ρ̄2 is exactly 0.5) and its analysis."""
    mesh, rho2 = _layered_design()
    out = tmp_path_factory.mktemp("layered")
    return _analysed(mesh, rho2, out, ("fixed", "follower")), out


def test_layered_block_has_two_body_fitted_regions(block):
    from pacto_ng.post.materials import interface_length, material_areas

    res, out = block
    rm = res.remeshed
    assert rm.materials == "body-fitted"
    areas = material_areas(rm.mesh)
    assert set(areas) == {"soft", "stiff"}
    assert areas["soft"] == pytest.approx(0.5 * W * H, rel=1e-6)
    assert areas["stiff"] == pytest.approx(0.5 * W * H, rel=1e-6)
    assert interface_length(rm.mesh) == pytest.approx(W, rel=1e-6)
    assert rm.wetted_length == pytest.approx(W, rel=1e-9)  # the top only, not the interface
    # every element lies wholly on its side of y = H/2
    for el in rm.mesh.Elements():
        ys = [rm.mesh[v].point[1] for v in el.vertices]
        if el.mat == "stiff":
            assert min(ys) >= 0.5 * H - 1e-9 * H
        else:
            assert max(ys) <= 0.5 * H + 1e-9 * H
    assert (out / "materials.png").stat().st_size > 0


@pytest.mark.parametrize("kind", ["fixed", "follower"])
def test_layered_block_matches_the_uniaxial_closed_form(block, kind):
    res, _ = block
    sw = res.sweeps[kind]
    assert sw.converged.all()
    for P, delta in zip(sw.pressures, sw.delta):
        exact = -layered_top_displacement(P, E1, E2)  # Δ = -u_y at the top
        assert delta == pytest.approx(exact, rel=1e-8)
    # the check discriminates: one modulus for the whole part is far off
    one = -layered_top_displacement(PRESSURES[-1], E1, E1)
    assert abs(one - sw.delta[-1]) > 0.5 * abs(sw.delta[-1])


def test_layered_block_files_name_the_materials(block, tmp_path):
    """remeshed.vtu: cell data material (named by field data) and E; the MSH: the materials as
    physical groups of the triangles, read back with their areas."""
    import meshio

    from pacto_ng.post.cli_commands import write_msh

    res, out = block
    m = meshio.read(out / "remeshed.vtu")
    ids = np.concatenate(m.cell_data["material"])
    E = np.concatenate(m.cell_data["E"])
    tri = np.concatenate([b.data for b in m.cells])
    p = m.points[:, :2]
    area = 0.5 * np.abs(_cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]))
    for name in ("soft", "stiff"):
        mine = np.concatenate(m.cell_data[f"material_{name}"]) == 1
        assert area[mine].sum() == pytest.approx(0.5 * W * H, rel=1e-6)
        assert np.all(E[mine] == {"soft": E1, "stiff": E2}[name])
        assert np.all(ids[mine] == ids[mine][0]) and not np.any(ids[~mine] == ids[mine][0])
    write_msh(tmp_path / "block.msh", res.remeshed.mesh)
    g = meshio.read(tmp_path / "block.msh")
    groups = {int(v[0]): k for k, v in g.field_data.items()}
    for block_, phys in zip(g.cells, g.cell_data["gmsh:physical"]):
        if block_.type != "triangle":
            continue
        q = g.points[:, :2]
        t = block_.data
        a = 0.5 * np.abs(_cross(q[t[:, 1]] - q[t[:, 0]], q[t[:, 2]] - q[t[:, 0]]))
        got = {groups[i]: a[phys == i].sum() for i in np.unique(phys)}
        assert got == pytest.approx({"soft": 0.5 * W * H, "stiff": 0.5 * W * H}, rel=1e-6)


@pytest.fixture(scope="module")
def block_elementwise(tmp_path_factory):
    """The layered block with the body-fitted cut made to fail: the fallback meshes the
    one-material part and gives each element the material of ρ̄2 at its centroid."""
    import importlib

    def fail(*args, **kwargs):
        raise RuntimeError("forced for the test")

    remesh = importlib.import_module("pacto_ng.post.remesh")  # the module, not the function
    mesh, rho2 = _layered_design()
    out = tmp_path_factory.mktemp("layered_elementwise")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(remesh, "split_part", fail)
        return _analysed(mesh, rho2, out, ("fixed",))


def test_elementwise_fallback_assigns_each_element_by_its_centroid(block_elementwise):
    """The nodal ρ̄2 of the layered design is 0 up to y = 3H/8, 0.5 at y = H/2 and 1 from
    y = 5H/8, linear between: ρ̄2 >= 0.5 at a centroid exactly where the centroid lies at or
    above H/2.  No interface boundary; the staircase moves at most one element row (maxh H/6)
    of area; the response lies between the soft-only and the stiff-only closed forms."""
    from pacto_ng.post.materials import interface_length, material_areas

    res = block_elementwise
    rm = res.remeshed
    assert rm.materials == "element-wise (the interface as a boundary failed: forced for the test)"
    for el in rm.mesh.Elements():
        yc = np.mean([rm.mesh[v].point[1] for v in el.vertices])
        assert el.mat == ("stiff" if yc >= 0.5 * H else "soft"), (yc, el.mat)
    areas = material_areas(rm.mesh)
    assert set(areas) == {"soft", "stiff"} and interface_length(rm.mesh) == 0.0
    assert sum(areas.values()) == pytest.approx(W * H, rel=1e-9)
    assert abs(areas["stiff"] - 0.5 * W * H) <= W * H / 6
    sw = res.sweeps["fixed"]
    assert sw.converged.all()
    for P, delta in zip(sw.pressures, sw.delta):
        stiff_only, soft_only = (-layered_top_displacement(P, E, E) for E in (E2, E1))
        assert stiff_only < delta < soft_only


# ------------------------------------------------------------------------------------------
# end to end: mm-gripper
MM_PRESSURES = [1e3, 1e4]


@pytest.fixture(scope="module")
def mm_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("two_materials") / "mm"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        assert main(["run", "mm-gripper", "--maxh", "0.008", "--iterations", "20",
                     "--out", str(out), "--quiet", "--no-refine"]) == 0
        assert main(["analyse", str(out), "--pressures", ",".join(map(str, MM_PRESSURES)),
                     "--quiet"]) == 0
        for fmt in ("stl", "vtk", "msh"):
            assert main(["export", str(out), "--format", fmt, "--no-mirror", "--units", "m",
                         "--quiet"]) == 0  # the half, in metres
    return out


@pytest.fixture(scope="module")
def mm_analysis(mm_run):
    return json.loads((mm_run / "analysis" / "analysis.json").read_text())


def test_mm_part_holds_both_materials(mm_run, mm_analysis):
    import meshio

    a = mm_analysis
    assert a["settings"]["E"] == {"soft": 3e8, "stiff": 3e9}
    assert a["settings"]["threshold2"] == 0.5
    areas = a["materials"]["remeshed"]
    assert set(areas) == {"soft", "stiff"} and min(areas.values()) > 0
    assert sum(areas.values()) == pytest.approx(a["part"]["measures"]["remeshed"], rel=1e-10)
    assert a["materials"]["mode"] == "body-fitted" and a["materials"]["interface_length"] > 0
    assert a["materials"]["E"] == a["settings"]["E"]
    # the areas again from remeshed.vtu's cells and their material ids
    m = meshio.read(mm_run / "analysis" / "remeshed.vtu")
    ids = np.concatenate(m.cell_data["material"])
    tri = np.concatenate([b.data for b in m.cells])
    p = m.points[:, :2]
    area = 0.5 * np.abs(_cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]))
    for name in ("soft", "stiff"):
        mine = np.concatenate(m.cell_data[f"material_{name}"]) == 1
        assert area[mine].sum() == pytest.approx(areas[name], rel=1e-9)
        assert np.all(np.concatenate(m.cell_data["E"])[mine] == a["settings"]["E"][name])
    assert set(np.unique(ids)) == {1, 2}
    report = (mm_run / "analysis" / "report.md").read_text()
    assert "**Two materials**" in report and "materials.png" in report
    assert (mm_run / "analysis" / "materials.png").stat().st_size > 0


def test_mm_delta_is_read_from_the_displacement_field(mm_run, mm_analysis):
    """The follower state at the largest pressure (remeshed.vtu's u): Δ = d·u at the vertex
    nearest the case's output point, d from the case (as test_two_ports does)."""
    import meshio

    from pacto_ng.case import get_case

    case = get_case("mm-gripper")
    params = case.parameters(json.loads((mm_run / "params.json").read_text())["params"])
    points = dict(case.geometry(params).points)  # the case's named points (its layout)
    (port,) = case.make_setup(params).ports
    assert mm_analysis["deformed_state"] == {"kind": "follower", "pressure": MM_PRESSURES[-1]}
    ref = meshio.read(mm_run / "analysis" / "remeshed.vtu")
    k = int(np.argmin(np.linalg.norm(ref.points[:, :2] - points[port.region], axis=1)))
    d = np.asarray(port.direction, dtype=float)
    delta = port.weight * float(d @ ref.point_data["u"][k, :2])
    row = mm_analysis["pressures"][-1]
    assert row["follower"]["delta"] == pytest.approx(delta, rel=1e-9)
    for kind in ("darcy", "fixed", "follower"):
        assert all(r[kind]["converged"] for r in mm_analysis["pressures"])
    # a linear run's expected Δ scales with the pressure: the design's Δ at the run's load
    # and the part's order (summary.json's at the run's order 1 when rebuilt)
    summary = json.loads((mm_run / "summary.json").read_text())
    run = mm_analysis["run"]
    assert run["output_displacement_rebuilt"] == pytest.approx(
        summary["output_displacement"], rel=1e-8)
    for r in mm_analysis["pressures"]:
        assert r["expected"] == pytest.approx(
            run["output_displacement_at_order"] * r["pressure"] / params.load, rel=1e-8)


def test_mm_export_writes_the_whole_part(mm_run, mm_analysis):
    """STL closed with volume = the part's area × t; VTK and MSH name both materials with
    the analysed part's areas."""
    import meshio
    import pyvista as pv

    areas = mm_analysis["materials"]["remeshed"]
    t = mm_analysis["settings"]["thickness"]
    stl = pv.read(mm_run / "export" / "design.stl")
    assert stl.extract_feature_edges(boundary_edges=True, feature_edges=False,
                                     manifold_edges=False, non_manifold_edges=True).n_cells == 0
    assert stl.volume == pytest.approx(sum(areas.values()) * t, rel=1e-6)
    v = meshio.read(mm_run / "export" / "design.vtk")
    tri = np.concatenate([b.data for b in v.cells])
    p = v.points[:, :2]
    area = 0.5 * np.abs(_cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]))
    got = {name: area[np.concatenate(v.cell_data[f"material_{name}"]) == 1].sum()
           for name in ("soft", "stiff")}
    assert got == pytest.approx(areas, rel=1e-9)
    g = meshio.read(mm_run / "export" / "design.msh")
    assert {"soft", "stiff", "interface", "pressure", "fixed"} <= set(g.field_data)
