"""The loads of a part's analysis (post.part_analysis.PartAnalysis), Neo-Hookean: fixed,
follower and Darcy pressure (the kinds of ``pacto analyse``).

Closed forms: the thick-walled cylinder (Lamé) under internal pressure P in plane strain,
``u_r(a) = (1+ν) a² P / (E (b² - a²)) ((1-2ν) a + b²/a)``; and the same cylinder under a
radial body force ``f_r = -dp/dr`` with traction-free faces, whose small-strain solution
follows from ``(λ+2μ) d/dr((1/r) d(r u)/dr) = -f_r``:
``u = I(r) / ((λ+2μ) r) + A r + B / r`` with ``I(r) = ∫_a^r s p(s) ds`` and ``A``, ``B`` from
``σ_r(a) = σ_r(b) = 0``, ``σ_r = p - 2μ/(λ+2μ) I/r² + 2(λ+μ) A - 2μ B/r²``.  (These tests
checked the Neo-Hookean ``Reanalysis`` class that PartAnalysis replaced; the figures are the
same.)
"""
import numpy as np
import pytest

from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.physics.walls import outward_normal, pressure_body_force
from pacto_ng.post.part_analysis import PartAnalysis

E, NU, A, B = 1e6, 0.3, 1.0, 2.0
NEO = Parameters(model="neohookean", E1=E, E0=1e-3 * E, E2=E, nu=NU, thickness=1.0,
                 plane="strain")
RING = dict(params=NEO, supports=Supports(fix_x=("left",), fix_y=("bottom",)),
            ports=Port("output", (1.0, 0.0)))


def lame_inner(P):
    return (1 + NU) * A * A * P / (E * (B * B - A * A)) * ((1 - 2 * NU) * A + B * B / A)


def body_force_inner(pfun):
    """u_r(a) of the small-strain cylinder under f_r = -p'(r), traction-free faces."""
    from scipy.integrate import quad

    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    M = lam + 2 * mu
    Ib = quad(lambda s: s * pfun(s), A, B, epsabs=0, epsrel=1e-13)[0]
    mat = np.array([[2 * (lam + mu), -2 * mu / A**2], [2 * (lam + mu), -2 * mu / B**2]])
    ca, cb = np.linalg.solve(mat, -np.array([pfun(A), pfun(B) - 2 * mu / M * Ib / B**2]))
    return ca * A + cb / A


def test_outward_normal_points_out_of_the_solid(ring_quarter):
    """The inner arc, which NGSolve orients into the body: N0 = -x/a there, so
    ∫ N0·x ds = -a (π a / 2); over the whole boundary the divergence theorem's 2 |Ω|."""
    import ngsolve as ng

    xy = ng.CF((ng.x, ng.y))
    arc = ng.Integrate(outward_normal(ring_quarter, "pressure") * xy, ring_quarter, ng.BND,
                       definedon=ring_quarter.Boundaries("pressure"), order=5)
    assert arc == pytest.approx(-A * np.pi * A / 2, rel=1e-6)
    own = ng.Integrate(ng.specialcf.normal(2) * xy, ring_quarter, ng.BND,
                       definedon=ring_quarter.Boundaries("pressure"), order=5)
    assert own == pytest.approx(-arc, rel=1e-12)  # NGSolve's own normal: the other way
    lhs = ng.Integrate(outward_normal(ring_quarter, "left|bottom|pressure|outer") * xy,
                       ring_quarter, ng.BND, order=5)
    assert lhs == pytest.approx(2 * ng.Integrate(1.0, ring_quarter, order=5), rel=1e-12)


def test_fixed_pressure_matches_lame(ring_quarter):
    """Small-strain limit, P = 1e-5 E: the Neo-Hookean departure from Lamé is ≈ 0.6 P/E
    (measured), so 1e-5 leaves room only for a discretisation error of the same size."""
    P = 1e-5 * E
    sw = PartAnalysis(ring_quarter, "fixed", order=3, **RING).sweep([P])
    assert sw.points[0].converged
    assert sw.delta[0] > 0  # the pressure pushes the inner wall outwards
    assert sw.delta[0] == pytest.approx(lame_inner(P), rel=1e-5)
    assert sw.points[0].max_u == pytest.approx(sw.delta[0], rel=1e-6)  # |u| peaks at r = a


def test_several_ports_add_up_with_their_weights():
    """Ports at (a, 0) along x and at (0, a) along y, Δ = 2 u_x(a, 0) - 0.5 u_y(0, a): both are
    Lamé's u_r(a), so Δ = 1.5 u_r(a); every port's own d·u is recorded."""
    import ngsolve as ng
    from netgen import occ

    from conftest import ring_quarter_shape

    shape = ring_quarter_shape(A, B)
    shape.vertices.Nearest((A, 0, 0)).name = "output"
    shape.vertices.Nearest((0, A, 0)).name = "top"
    mesh = ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.1))
    mesh.Curve(3)
    P = 1e-5 * E
    ports = (Port("output", (1.0, 0.0), weight=2.0), Port("top", (0.0, 1.0), weight=-0.5))
    sw = PartAnalysis(mesh, "fixed", order=3, **{**RING, "ports": ports}).sweep([P])
    assert sw.points[0].converged
    assert sw.points[0].ports == pytest.approx((lame_inner(P), lame_inner(P)), rel=1e-5)
    assert sw.delta[0] == pytest.approx(1.5 * lame_inner(P), rel=1e-5)
    row = sw.table()[0]
    assert (row["port_output"], row["port_top"]) == sw.points[0].ports
    with pytest.raises(ValueError, match="two output ports on 'output'"):
        PartAnalysis(mesh, "fixed", **{**RING, "ports": (Port("output", (1.0, 0.0)),
                                                         Port("output", (0.0, 1.0)))})


def test_follower_equals_fixed_as_pressure_vanishes(ring_quarter_straight):
    """The follower and the fixed load differ by O(P²) in Δ: the relative difference is
    proportional to P, so it falls tenfold with P."""
    Ps = [1e-5 * E, 1e-4 * E]
    fol = PartAnalysis(ring_quarter_straight, "follower", order=2, **RING).sweep(Ps)
    fix = PartAnalysis(ring_quarter_straight, "fixed", order=2, **RING).sweep(Ps)
    assert fol.converged.all() and fix.converged.all()
    rel = np.abs(fol.delta / fix.delta - 1.0)
    assert rel[0] < 1e-4
    assert rel[0] / rel[1] == pytest.approx(0.1, rel=0.01)


def test_follower_tangent_is_the_derivative_of_the_residual(ring_quarter_straight):
    """At a deformed state (P = 0.05 E, |u| ≈ 10 % of a): the assembled tangent applied to a
    direction equals the central difference of the residual, and it is unsymmetric (the
    load stiffness of the follower pressure)."""
    r = PartAnalysis(ring_quarter_straight, "follower", order=2, **RING)
    pt = r.solve(0.05 * E)
    assert pt.converged and pt.max_u > 0.05 * A
    a, u0 = r.mech.a, r.mech.gfu.vec
    rng = np.random.default_rng(1)
    w, z = u0.CreateVector(), u0.CreateVector()
    w.FV().NumPy()[:] = rng.standard_normal(len(w)) * 1e-2
    z.FV().NumPy()[:] = rng.standard_normal(len(z)) * 1e-2
    a.AssembleLinearization(u0)
    Kw = (a.mat * w).Evaluate().FV().NumPy()
    Kz = (a.mat * z).Evaluate().FV().NumPy()
    eps = 1e-6
    up, um, rp, rm = (u0.CreateVector() for _ in range(4))
    up.data = u0 + eps * w
    um.data = u0 - eps * w
    a.Apply(up, rp)
    a.Apply(um, rm)
    fd = (rp.FV().NumPy() - rm.FV().NumPy()) / (2 * eps)
    assert np.linalg.norm(fd - Kw) < 1e-7 * np.linalg.norm(Kw)
    asym = abs(z.FV().NumPy() @ Kw - w.FV().NumPy() @ Kz)
    assert asym > 1e-6 * abs(z.FV().NumPy() @ Kw)


def test_darcy_body_matches_axisymmetric_solution(ring_quarter):
    """The ``darcy`` kind with p = P exp(-(r-a)/δ), δ = 0.2, passed as a body force -∇p: Δ
    matches the closed-form small-strain solution (P = 1e-5 E; the Neo-Hookean departure is
    O(P/E), as for the Lamé check).  The body force scales with P / P_in: at P_in / 2 half of
    it."""
    import ngsolve as ng

    P, delta = 1e-5 * E, 0.2
    p = P * ng.exp(-(ng.sqrt(ng.x**2 + ng.y**2) - A) / delta)
    sw = PartAnalysis(ring_quarter, "darcy", order=3, body=pressure_body_force(p, order=3),
                      body_pressure=P, **RING).sweep([0.5 * P, P])
    ref = body_force_inner(lambda s: P * np.exp(-(s - A) / delta))
    assert sw.delta[1] == pytest.approx(ref, rel=1e-5)
    assert sw.delta[0] == pytest.approx(0.5 * ref, rel=1e-5)


def test_failure_is_reported_and_the_sweep_stops(ring_quarter_straight):
    params = NEO.replace(newton_max_iter=3, newton_min_increment=0.5)
    sw = PartAnalysis(ring_quarter_straight, "fixed", order=2,
                      **{**RING, "params": params}).sweep([1e-5 * E, 3.0 * E, 4.0 * E])
    assert sw.converged.tolist() == [True, False, False]
    assert sw.points[1].load_reached < 1.0 and np.isnan(sw.delta[1])
    assert sw.points[2].iterations == 0  # not attempted
    assert sw.displacement().vec.FV().NumPy() @ sw.states[0] > 0  # last converged state


def test_chamber_pipeline_follower_tends_to_fixed(chamber_sweeps):
    """Threshold -> remesh -> sweep on the synthetic chamber (E = 1e8, t = 1 mm, output spring
    1e4 N/m): every pressure converges with det F > 0, and the follower/fixed difference falls
    tenfold with the pressure (first order in P)."""
    res = chamber_sweeps
    for sw in res.values():
        assert sw.converged.all()
        assert all(0.0 < pt.min_j < 1.0 + 1e-3 for pt in sw.points)
        assert all(1 <= pt.iterations <= 6 for pt in sw.points)
    rel = np.abs(res["follower"].delta / res["fixed"].delta - 1.0)
    assert rel[0] / rel[1] == pytest.approx(0.1, rel=0.05)  # 1e3 vs 1e4 Pa: asymptotic range


def test_unknown_kind_missing_boundary_and_missing_body_raise(ring_quarter):
    with pytest.raises(ValueError, match="kind"):
        PartAnalysis(ring_quarter, "dead", **RING)
    with pytest.raises(ValueError, match="wet"):
        PartAnalysis(ring_quarter, "fixed", boundary="wet", **RING)
    with pytest.raises(ValueError, match="body"):
        PartAnalysis(ring_quarter, "darcy", **RING)


@pytest.mark.slow
def test_darcy_pressure_block_tends_to_the_boundary_pressure():
    """The Darcy block's pressure of the chamber design, as a fixed body load on the remeshed
    solid, approaches the fixed boundary pressure on the wetted cavity wall as the penetration
    depth Δs shrinks (the remesh, maxh = 0.5 mm, resolves Δs; measured 6e-3 at Δs = 4 mm and
    3e-4 at 1 mm)."""
    import ngsolve as ng

    from conftest import CHAMBER_PARAMS, P_IN, chamber_density, chamber_layout, chamber_pressure
    from pacto_ng.mesh import structured_mesh
    from pacto_ng.physics.darcy import DarcyPressure
    from pacto_ng.post.remesh import remesh
    from pacto_ng.post.threshold import threshold

    mesh = structured_mesh(chamber_layout(), 100, 50)
    rho = chamber_density(mesh)
    rm = remesh(threshold(mesh, rho), 0.0005, pressure=chamber_pressure)
    kw = dict(params=Parameters(**CHAMBER_PARAMS), supports=Supports(clamp=("fixed",)),
              ports=Port("output", (0.0, -1.0), 1e4), order=2)
    fixed = PartAnalysis(rm.mesh, "fixed", **kw).sweep([P_IN]).delta[0]
    rel = []
    for ds in (0.004, 0.001):
        block = DarcyPressure(mesh, inlet="inlet", zero="free", p_in=P_IN, delta_s=ds)
        p = ng.GridFunction(block.fes)
        p.vec.data = block.forward(rho)
        sw = PartAnalysis(rm.mesh, "darcy", body=pressure_body_force(p), body_pressure=P_IN,
                          **kw).sweep([P_IN])
        rel.append(abs(sw.delta[0] / fixed - 1.0))
    assert rel[1] < rel[0] / 4 and rel[1] < 1e-3
