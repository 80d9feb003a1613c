"""Frictionless self-contact in a part's analysis (pacto_ng/physics/contact.py), in 2D and 3D.

A block 1 x 1 m with a slot open at one end (0.02 m high, from x = 0.3 to the end), clamped
on the side the slot does not reach, is squeezed by a pressure of 3 kPa on its top and bottom
faces (E = 1 MPa): the slot's two walls close at its open end.  Without contact they pass
through each other (the walls' vertical gap falls to -0.037 m, linear, and -0.039 m,
Neo-Hookean); with the slot's walls in self-contact the gap stays at the penalty's overlap,
contact pressure / 2k, which shrinks tenfold when k grows tenfold (k = 1e2 and 1e3 E/h:
measured -1.70e-6 and -1.69e-7 m linear, -1.73e-6 and -1.72e-7 m Neo-Hookean)."""
import numpy as np
import pytest
from netgen.occ import Box, MoveTo, OCCGeometry, X, Y
from ngsolve import Mesh

from pacto_ng import Parameters, Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.physics.contact import PAIRS_SETTLE
from pacto_ng.post.part_analysis import PartAnalysis

LOW, HIGH = 0.49, 0.51  # the slot's walls


def _name_walls(walls) -> None:
    """Name a slotted block's edges (2D) or faces (3D): ``fixed`` at x = 0, ``pressure`` on
    top and bottom, ``slot`` the slot's walls, ``free`` the rest."""
    walls.name = "free"
    walls.Min(X).name = "fixed"
    walls.Max(Y).name = "pressure"
    walls.Min(Y).name = "pressure"
    for wall in walls:
        if LOW - 0.01 < wall.center.y < HIGH + 0.01 and wall.center.x > 0.29:
            wall.name = "slot"


def slotted(dim: int = 2):
    """The slotted block (module docstring), in 3D extruded 0.2 m."""
    if dim == 2:
        body = (MoveTo(0, 0).Rectangle(1, 1).Face()
                - MoveTo(0.3, LOW).Rectangle(0.8, 0.02).Face())
        _name_walls(body.edges)
        return Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.05))
    body = Box((0, 0, 0), (1, 1, 0.2)) - Box((0.3, LOW, -0.1), (1.1, HIGH, 0.3))
    _name_walls(body.faces)
    return Mesh(OCCGeometry(body).GenerateMesh(maxh=0.2))


def smallest_gap(mesh, analysis) -> float:
    """The least vertical gap between the slot's walls along it (3D: at mid-depth)."""
    u = analysis.mech.u
    at = (lambda x, y: mesh(x, y)) if mesh.dim == 2 else (lambda x, y: mesh(x, y, 0.1))
    return min(HIGH + u(at(x, HIGH))[1] - LOW - u(at(x, LOW))[1]
               for x in np.linspace(0.35, 0.99, 30))


def squeeze(mesh, model: str, contact=(), penalty: float = 1e3, *, nu: float = 0.3,
            formulation: str = "auto"):
    params = Parameters(model=model, E1=1e6, E0=1.0, nu=nu, plane="strain", thickness=1.0,
                        order=2, formulation=formulation)
    an = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("fixed",)),
                      ports=Port("pressure", (0.0, -1.0)), contact=contact,
                      contact_penalty=penalty)
    point = an.solve(3e3)
    assert point.converged
    return smallest_gap(mesh, an)


@pytest.mark.parametrize("model", ["linear", "neohookean"])
def test_slot_walls_pass_through_each_other_without_contact_and_not_with_it(model):
    mesh = slotted()
    assert squeeze(mesh, model) < -0.03
    coarse, fine = (squeeze(mesh, model, ("slot",), penalty=k) for k in (1e2, 1e3))
    assert -1e-4 * (HIGH - LOW) < fine < 0 and coarse < 0
    assert coarse / fine == pytest.approx(10.0, rel=0.05)  # the overlap is p / k


def test_the_mixed_formulation_keeps_nearly_incompressible_walls_apart():
    """ν = 0.49, the silicone regime, where the part's analysis takes the mixed formulation
    (u with an element dilatation and pressure): the walls pass through each other without
    contact and not with it, the overlap the penalty's p / k."""
    mesh = slotted()
    kw = dict(nu=0.49, formulation="mixed")
    assert squeeze(mesh, "neohookean", **kw) < -(HIGH - LOW)  # -0.026 m: through the slot
    coarse, fine = (squeeze(mesh, "neohookean", ("slot",), penalty=k, **kw) for k in (1e2, 1e3))
    assert -1e-4 * (HIGH - LOW) < fine < 0 and coarse < 0
    assert coarse / fine == pytest.approx(10.0, rel=0.05)


def test_walls_that_slide_along_each_other_settle():
    """The slotted block loaded on its top face only (Neo-Hookean, 3 then 10 kPa): the upper
    wall slides along the lower one as the block bends, and the pairs found at one state no
    longer hold at the next.  The pairs follow the load ramp and are paired anew until they
    hold: at 10 kPa the walls touch over 0.106 m and stay apart to the penalty's overlap
    (before the pairs followed the ramp and the residual's line search, 2026-12-07, the
    residual after pairing anew stayed at 0.11 of the load: no equilibrium)."""
    body = MoveTo(0, 0).Rectangle(1, 1).Face() - MoveTo(0.3, LOW).Rectangle(0.8, 0.02).Face()
    _name_walls(body.edges)
    body.edges.Min(Y).name = "free"  # the pressure on the top face only
    mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.05))
    params = Parameters(model="neohookean", E1=1e6, E0=1.0, nu=0.3, plane="strain",
                        thickness=1.0, order=2)
    an = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("fixed",)),
                      ports=Port("pressure", (0.0, -1.0)), contact=("slot",))
    assert an.solve(3e3).converged
    point = an.solve(1e4)
    assert point.converged and point.contact_area > 0.05
    assert smallest_gap(mesh, an) > -1e-3 * (HIGH - LOW)
    assert an.mech.pairs_mismatch() <= PAIRS_SETTLE  # paired anew, the equilibrium holds


def two_blocks(dim: int, g0: float):
    """Two unit squares (2D) or cubes (3D), one above the other in y with a gap ``g0``:
    ``bottom`` the lower's bottom, ``lo_top`` and ``up_bottom`` the facing walls,
    ``pressure`` the upper's top, ``lo_left``/``up_left`` their faces x = 0, and in 3D
    ``lo_back``/``up_back`` their faces z = 0."""
    from netgen.occ import Compound, Z

    if dim == 2:
        lo, up = MoveTo(0, 0).Rectangle(1, 1).Face(), MoveTo(0, 1 + g0).Rectangle(1, 1).Face()
        walls = lambda body: body.edges  # noqa: E731
    else:
        lo, up = Box((0, 0, 0), (1, 1, 1)), Box((0, 1 + g0, 0), (1, 2 + g0, 1))
        walls = lambda body: body.faces  # noqa: E731
    for body, tag in ((lo, "lo"), (up, "up")):
        walls(body).name = "free"
        walls(body).Min(X).name = f"{tag}_left"
        if dim == 3:
            walls(body).Min(Z).name = f"{tag}_back"
    walls(lo).Min(Y).name, walls(lo).Max(Y).name = "bottom", "lo_top"
    walls(up).Max(Y).name, walls(up).Min(Y).name = "pressure", "up_bottom"
    return Mesh(OCCGeometry(Compound([lo, up]), dim=dim).GenerateMesh(maxh=0.25 if dim == 2
                                                                       else 0.5))


@pytest.mark.parametrize("dim", [2, 3])
def test_two_blocks_pressed_together_against_a_spring_move_as_the_closed_form_says(dim):
    """Two unit blocks, one above the other with a gap g0 = 0.1 mm (E = 1 MPa, ν = 0.3,
    linear; 2D in plane strain): the lower stands on its bottom, both are held in x on their
    faces x = 0 (and in z on their faces z = 0), and the upper's top carries a pressure
    P = 1 kPa against a spring ks = 1 MN/m on its mean displacement Δ.  Without contact the
    upper block passes through the lower: Δ = P / ks.  With contact a force F = P - ks Δ
    passes through both blocks in uniaxial stress, each shortened by F c / E (c = 1 - ν² in
    plane strain, 1 in 3D, where the sides are free), and the walls overlap by F / (2k):
    Δ = (a P + g0) / (1 + ks a) with a = 2 c / E + 1 / (2k).  The analysis reports the walls
    in contact over the whole face, with the force F and the largest contact pressure F per
    unit area (the uniform one)."""
    from ngsolve import Integrate

    g0, E, nu, P, ks = 1e-4, 1e6, 0.3, 1e3, 1e6
    mesh = two_blocks(dim, g0)
    params = Parameters(model="linear", E1=E, E0=1.0, nu=nu, plane="strain", thickness=1.0,
                        order=2)
    down = (0.0, -1.0, 0.0)[:dim]
    held = dict(fix_y=("bottom",), fix_x=("lo_left", "up_left"))
    if dim == 3:
        held["fix_z"] = ("lo_back", "up_back")
    got, points = [], []
    for contact in ((), ("lo_top", "up_bottom")):
        an = PartAnalysis(mesh, "fixed", params=params, supports=Supports(**held),
                          ports=Port("pressure", down, spring=ks), contact=contact)
        point = an.solve(P)
        assert point.converged
        got.append(point.delta)
        points.append(point)
    k = 1e3 * E / (Integrate(1.0, mesh) / mesh.ne) ** (1.0 / dim)
    a = 2 * (1 - nu ** 2 if dim == 2 else 1.0) / E + 1 / (2 * k)
    assert got[0] == pytest.approx(P / ks, rel=1e-12)
    assert got[1] == pytest.approx((a * P + g0) / (1 + ks * a), rel=1e-12)
    force = P - ks * got[1]  # through the blocks, per unit area (2D: thickness and width)
    assert force > 0 and points[0].contact_area is None
    # the contact's measures: the whole unit face, and the force the blocks carry
    assert points[1].contact_area == pytest.approx(1.0, rel=1e-9)
    assert points[1].contact_force == pytest.approx(force, rel=1e-9)
    # the largest contact pressure: the uniform one, force over area (measured 1.8e-10 off in
    # 2D; 3.0e-6 in 3D, where the lower block's top and the upper's bottom are triangulated
    # with different diagonals, and a vertex's force from the other wall is its hat function
    # summed at that wall's quadrature points, exact only where the two meshes match)
    assert points[0].contact_pressure is None
    assert points[1].contact_pressure == pytest.approx(force, rel=1e-9 if dim == 2 else 1e-5)


def test_slot_walls_do_not_pass_through_each_other_in_3d():
    """The slotted block extruded 0.2 m (711 tetrahedra, linear, order 1): without contact
    the slot's walls overlap by 0.032 m at mid-depth; with contact by at most 1e-3 of the
    slot's height (measured 4.3e-6 m), touching over part of their area."""
    mesh = slotted(3)
    params = Parameters(model="linear", E1=1e6, E0=1.0, nu=0.3, thickness=1.0, order=1)
    gaps, points = [], []
    for contact in ((), ("slot",)):
        an = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("fixed",)),
                          ports=Port("pressure", (0.0, -1.0, 0.0)), contact=contact)
        points.append(an.solve(3e3))
        assert points[-1].converged
        gaps.append(smallest_gap(mesh, an))
    assert gaps[0] < -0.03
    assert gaps[1] > -1e-3 * (HIGH - LOW)
    slot_area = 0.7 * 0.2
    assert 0 < points[1].contact_area < slot_area and points[1].contact_force > 0


