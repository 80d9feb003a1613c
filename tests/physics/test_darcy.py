"""The Darcy–drainage pressure (docs/theory.md §2, thesis ch. 3 and Appendix B) against closed forms.

References are independent of the code under test: exponential / cosh / Bessel closed forms,
a 1D finite-element solver written here in numpy, and the divergence theorem for the load.
Thesis Appendix B lost its figures; our boundary conditions are stated per scenario.  Where the
thesis puts p = 0 on the top and bottom of the beam we say so; elsewhere those walls carry no
flux (the walls of a chamber), so that a void region keeps the inlet pressure.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from pacto_ng.mesh import Layout, Region, Segment, netgen_mesh, structured_mesh
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import Compliance, darcy_body

DS = 0.002  # thesis Table 6.1 penetration depth Δs
R_RATIO = 0.1  # thesis Table 6.1 r
P_IN = 1e4  # thesis App. B pressure


# -- independent reference implementations -------------------------------------------------------
def heaviside(rho, eta, beta):
    return ((np.tanh(beta * eta) + np.tanh(beta * (rho - eta)))
            / (np.tanh(beta * eta) + np.tanh(beta * (1.0 - eta))))


def coefficients(rho, Kv=1.0, Ks=1e-7, r=R_RATIO, ds=DS):
    """K (thesis eq. 3.2) and D (thesis eq. 3.4) with the Table 6.1 steps."""
    rho = np.asarray(rho, dtype=float)
    K = Kv - (Kv - Ks) * heaviside(rho, 0.3, 10.0)
    D = (np.log(r) / ds) ** 2 * Ks * heaviside(rho, 0.2, 10.0)
    return K, D


def reference_1d(rho_cells, length, p_left, p_right, sub=40):
    """1D P1 solution of -(K p')' + D p = 0 with cell-wise constant K, D (``sub`` elements/cell)."""
    K, D = coefficients(rho_cells)
    Ke, De = np.repeat(K, sub), np.repeat(D, sub)
    n = len(Ke)
    h = length / n
    main = np.zeros(n + 1)
    main[:-1] += Ke / h + De * h / 3
    main[1:] += Ke / h + De * h / 3
    off = -Ke / h + De * h / 6
    A = sp.diags([off, main, off], [-1, 0, 1]).tocsr()
    p = np.zeros(n + 1)
    p[0], p[-1] = p_left, p_right
    rhs = -(A @ p)
    p[1:-1] = spl.spsolve(A[1:-1][:, 1:-1].tocsc(), rhs[1:-1])
    return np.linspace(0.0, length, n + 1), p


def pressure_gf(block, rho):
    from ngsolve import GridFunction

    gf = GridFunction(block.fes)
    gf.vec.data = block.forward(np.asarray(rho, dtype=float))
    return gf


def element_centres(mesh):
    pts = np.array([v.point for v in mesh.vertices])
    return np.array([pts[[v.nr for v in el.vertices]].mean(axis=0) for el in mesh.Elements()])


def strip(length, height, nelx, nely, inlet_left=True):
    segs = (Segment("inlet", (0, 0), (0, height)), Segment("zero", (length, 0), (length, height)))
    if not inlet_left:
        segs = (Segment("zero", (0, 0), (0, height)),
                Segment("inlet", (length, 0), (length, height)))
    return structured_mesh(Layout(length, height, segments=segs), nelx, nely)


# -- closed forms -------------------------------------------------------------------------------
@pytest.mark.parametrize("order, nelx", [(1, 100), (2, 50)])
def test_solid_strip_decays_exponentially(order, nelx):
    """ρ̄ = 1: p(x) = P_in exp(-|ln r| x / Δs) (the far end at 10 Δs adds < r^20)."""
    L, H = 10 * DS, 0.001
    mesh = strip(L, H, nelx, 2)
    gf = pressure_gf(DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=order),
                     np.ones(mesh.ne))
    at_ds = gf(mesh(DS, H / 2)) / P_IN
    assert abs(at_ds / R_RATIO - 1.0) < 0.02  # measured 0.09987 (P1), 0.10000 (P2)
    xs = np.linspace(0.0, 4 * DS, 33)
    vals = np.array([gf(mesh(x, H / 2)) for x in xs])
    rate = -np.polyfit(xs, np.log(vals), 1)[0]
    assert abs(rate / (np.log(1 / R_RATIO) / DS) - 1.0) < 0.01  # measured 1.0006 / 1.00001


@pytest.mark.parametrize("order", [1, 2])
def test_void_strip_is_linear(order):
    """ρ̄ = 0: K = Kv, D = 0 exactly, so p is harmonic: linear between the two ends."""
    L, H = 0.02, 0.004
    mesh = strip(L, H, 20, 4)
    gf = pressure_gf(DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=order),
                     np.zeros(mesh.ne))
    xs = np.linspace(0.0, L, 23)
    err = max(abs(gf(mesh(x, y)) - P_IN * (1 - x / L)) for x in xs for y in (0.0, H / 3, H))
    assert err < 1e-8 * P_IN


@pytest.mark.parametrize("order", [1, 2, 3])
def test_dirichlet_values_and_linearity_in_p_in(order):
    """p = P_in on the inlet, 0 on the zero boundary, at any order; p scales with P_in."""
    lay = Layout(0.02, 0.01, segments=(Segment("inlet", (0, 0), (0, 0.01)),
                                       Segment("zero", (0.02, 0), (0.02, 0.01))))
    mesh = netgen_mesh(lay, 0.003)
    rho = np.random.default_rng(3).uniform(0.0, 1.0, mesh.ne)
    block = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=order)
    gf = pressure_gf(block, rho)
    ys = np.linspace(0.0, 0.01, 11)[1:-1]
    assert max(abs(gf(mesh(0.0, y)) / P_IN - 1.0) for y in ys) < 1e-12
    assert max(abs(gf(mesh(0.02, y))) for y in ys) < 1e-12 * P_IN
    p1 = block.forward(rho).FV().NumPy().copy()
    block.p_in = 3.5 * P_IN
    p2 = block.forward(rho).FV().NumPy().copy()
    assert np.max(np.abs(p2 - 3.5 * p1)) < 1e-11 * np.max(np.abs(p2))


# -- thesis Appendix B ---------------------------------------------------------------------------
def beam(nelx=80, nely=40, W=0.02, H=0.01, zero_walls=True):
    """The App. B beam (scaled 1:10 so that Δs is resolved): inlet on the right edge, zero
    pressure on the left edge, and on top and bottom too if ``zero_walls`` (thesis B.1)."""
    segs = [Segment("inlet", (W, 0), (W, H)), Segment("zero", (0, 0), (0, H))]
    if zero_walls:
        segs += [Segment("zero", (0, 0), (W, 0)), Segment("zero", (0, H), (W, H))]
    return structured_mesh(Layout(W, H, segments=tuple(segs)), nelx, nely), W, H


def test_b1_solid_beam_drops_at_the_inlet_only():
    """B.1: ρ̄ = 1, inlet right, p = 0 on the remaining edges (thesis).  The pressure falls to
    r P_in at depth Δs and the body load sits in a layer of a few Δs at the inlet."""
    from ngsolve import Integrate, grad, sqrt, dx, IfPos, x

    mesh, W, H = beam()
    block = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=1)
    gf = pressure_gf(block, np.ones(mesh.ne))
    assert abs(gf(mesh(W - DS, H / 2)) / P_IN / R_RATIO - 1.0) < 0.02  # measured 0.0988
    deep = max(abs(gf(mesh(xx, yy))) for xx in np.linspace(0, W - 3 * DS, 30)
               for yy in np.linspace(0, H, 11))
    assert deep < 2e-3 * P_IN  # r^3 = 1e-3 in 1D; measured 9.1e-4
    g = sqrt(grad(gf) * grad(gf))
    near = Integrate(IfPos(x - (W - 2 * DS), g, 0.0) * dx, mesh)
    assert near / Integrate(g * dx, mesh) > 0.97  # 1 - r^2 = 0.99 in 1D; measured 0.993


def test_b2_solid_void_halves_drop_at_the_interface():
    """B.2: void right half (inlet side), solid left half; walls without flux.  The void keeps
    P_in; the drop happens in the solid, r P_in at Δs behind the interface."""
    mesh, W, H = beam(zero_walls=False)
    c = element_centres(mesh)
    rho = np.where(c[:, 0] < W / 2, 1.0, 0.0)
    gf = pressure_gf(DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=2), rho)
    void_min = min(gf(mesh(xx, yy)) for xx in np.linspace(W / 2, W, 21) for yy in (0, H / 2, H))
    assert void_min > (1.0 - 1e-5) * P_IN  # measured 1 - 1.2e-6
    for yy in (0.0, H / 2, H):
        assert abs(gf(mesh(W / 2 - DS, yy)) / P_IN / R_RATIO - 1.0) < 0.02  # measured 0.1000010
    assert gf(mesh(W / 2 - 4 * DS, H / 2)) < 2e-4 * P_IN  # r^4; measured 9.9e-5


@pytest.fixture(scope="module")
def semicircle_mesh():
    """Domain 0.04 x 0.02, solid half-disc of radius 0.008 on the middle of the left edge."""
    from netgen import occ
    from ngsolve import Mesh

    W, H, R = 0.04, 0.02, 0.008
    rect = occ.WorkPlane().Rectangle(W, H).Face()
    disc = occ.WorkPlane().Circle(0.0, H / 2, R).Face()
    solid, rest = rect * disc, rect - disc
    solid.faces.name, rest.faces.name = "solid", "void"
    solid.faces.maxh = DS / 5
    shape = occ.Glue([rest, solid])
    for e in shape.edges:
        e.name = "inlet" if abs(e.center.x - W) < 1e-9 else "wall"
    mesh = Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.002))
    return mesh, W, H, R


@pytest.mark.parametrize("order, tol", [(1, 5e-3), (2, 1e-3)])
def test_b3_solid_semicircle_matches_bessel(semicircle_mesh, order, tol):
    """B.3: the void around the half-disc keeps P_in (the only Dirichlet boundary is the inlet,
    the flat side lies on a wall); inside, p = P_in I0(kρ)/I0(kR), k = |ln r|/Δs, the same along
    every ray: no corner effects (the thesis's HFM model had them, its PDE model not)."""
    from scipy.special import i0

    mesh, W, H, R = semicircle_mesh
    rho = np.array([1.0 if el.mat == "solid" else 0.0 for el in mesh.Elements()])
    gf = pressure_gf(DarcyPressure(mesh, inlet="inlet", p_in=P_IN, order=order), rho)
    k = np.log(1 / R_RATIO) / DS
    for ang in (0.0, np.pi / 4, 0.45 * np.pi):
        for d in (0.0, DS / 2, DS, 2 * DS):
            rr = R - d
            val = gf(mesh(rr * np.cos(ang), H / 2 + rr * np.sin(ang))) / P_IN
            assert abs(val - i0(k * rr) / i0(k * R)) < tol  # at Δs: 0.1164 vs 0.1161 (P2)


@pytest.mark.parametrize("order, tol", [(1, 2e-3), (2, 3e-4)])
def test_b4_graded_beam_matches_1d_reference(order, tol):
    """B.4: ρ̄ = 1 - x/W by columns (solid left, void right), inlet right, zero left, walls
    without flux.  p follows the 1D solution of -(K p')' + D p = 0 (independent solver) and stays
    at P_in wherever ρ̄ < 0.75: the drop happens only where the material is nearly solid."""
    nelx, nely = 80, 4
    mesh, W, H = beam(nelx, nely, zero_walls=False)
    cols = 1.0 - (np.arange(nelx) + 0.5) / nelx
    gf = pressure_gf(DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=order),
                     np.tile(cols, nely))
    xs, ref = reference_1d(cols, W, 0.0, P_IN)
    fe = np.array([gf(mesh(xx, H / 2)) for xx in xs[::8]])
    assert np.max(np.abs(fe - ref[::8])) < tol * P_IN  # measured 9.8e-4 (P1), 1.2e-4 (P2)
    light = xs > 0.25 * W  # ρ̄ < 0.75 there
    assert fe[light[::8]].min() > 0.99 * P_IN
    assert np.all(np.diff(fe) >= -1e-9 * P_IN)  # monotone: falls towards the solid end


def test_b5_intermediate_densities_drop_only_above_06():
    """B.5: uniform ρ̄ = γ on the full-size thesis beam (0.2 m, inlet right, far end without flux).
    p = P_in cosh((L-d)/ℓ)/cosh(L/ℓ) with ℓ = sqrt(K(γ)/D(γ)); the pressure reaches r P_in inside
    the beam only for γ > 0.6 (thesis: "desired results for γ > 0.6")."""
    W, H = 0.2, 0.1
    mesh = structured_mesh(Layout(W, H, segments=(Segment("inlet", (W, 0), (W, H)),)), 400, 1)
    block = DarcyPressure(mesh, inlet="inlet", p_in=P_IN, order=2)
    depth = np.linspace(0.0, W, 41)
    minima = {}
    for gamma in (0.3, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0):
        gf = pressure_gf(block, np.full(mesh.ne, gamma))
        K, D = coefficients(gamma)
        ell = np.sqrt(K / D)
        exact = np.cosh((W - depth) / ell) / np.cosh(W / ell)
        fe = np.array([gf(mesh(W - d, H / 2)) for d in depth]) / P_IN
        assert np.max(np.abs(fe - exact)) < 1e-5  # measured 1.4e-6 at γ = 1, < 1e-8 else
        minima[gamma] = fe.min()
    assert all(minima[g] > 0.4 for g in (0.3, 0.5, 0.6))  # 0.44 at γ = 0.6
    assert all(minima[g] < R_RATIO for g in (0.7, 0.8, 0.9, 1.0))  # 0.037 at γ = 0.7


# -- the load -----------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["netgen", "quads"])
@pytest.mark.parametrize("order", [1, 2])
def test_load_on_solid_block_behind_void_inlet_region(kind, order):
    """A void chamber at the inlet, a solid block behind it: the body force -∇p on the solid
    elements equals the pressure on the wall, P_in H t (x direction); the void carries none."""
    from ngsolve import L2, GridFunction, Integrate, dx, grad

    L, H, t, P = 0.02, 0.01, 1e-3, 1e5
    lay = Layout(L, H, segments=(Segment("inlet", (0, 0), (0, H)), Segment("zero", (L, 0), (L, H))),
                 regions=(Region("chamber", "void", 0, 0, L / 2, H),))
    mesh = netgen_mesh(lay, 0.0005) if kind == "netgen" else structured_mesh(lay, 40, 20)
    block = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P, order=order)
    rho = np.array([0.0 if el.mat == "chamber" else 1.0 for el in mesh.Elements()])
    gp = pressure_gf(block, rho)
    solid = GridFunction(L2(mesh, order=0))
    solid.vec.FV().NumPy()[:] = rho
    DX = dx(intrules=block.rules)
    f_solid = np.array([Integrate(-t * solid * grad(gp)[i] * DX, mesh) for i in range(2)])
    f_void = np.array([Integrate(-t * (1 - solid) * grad(gp)[i] * DX, mesh) for i in range(2)])
    ref = P * H * t
    assert abs(f_solid[0] / ref - 1.0) < 1e-4  # measured 1 - 1.2e-6
    assert abs(f_solid[1]) / ref < 1e-3  # measured 2.8e-4 (unsymmetric P1 triangles)
    assert np.max(np.abs(f_void)) / ref < 1e-5  # measured 1.2e-6


def _pressure_mechanics(order=1, springs=()):
    from pacto_ng.interpolation import simp_cf
    from pacto_ng.physics.materials import linear_energy
    from pacto_ng.physics.mechanics import Mechanics, Supports

    L, H = 0.02, 0.01
    lay = Layout(L, H, segments=(Segment("inlet", (0, H), (0, 0)),
                                 Segment("fixed", (0, H), (L / 4, H)),
                                 Segment("zero", (L / 4, H), (L, H)),
                                 Segment("zero", (L, 0), (L, H)),
                                 Segment("symmetry", (0, 0), (L, 0))),
                 points=(("output", (L, 0)),))
    mesh = structured_mesh(lay, 20, 10)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=order)
    energy = lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4)
    mech = Mechanics(mesh, order=order, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)), springs=springs,
                     body=darcy_body("p"), thickness=1e-3, linear=True)
    rho = np.random.default_rng(5).uniform(0.3, 1.0, mesh.ne)
    return mesh, dar, mech, rho


def test_load_factor_scales_the_pressure_load():
    """Mechanics' load factor multiplies the Darcy load: u(s) = s u(1) for the linear model."""
    mesh, dar, mech, rho = _pressure_mechanics()
    p = dar.forward(rho)
    u1 = mech.forward(rho, p).FV().NumPy().copy()
    mech.target = 0.25
    u2 = mech.forward(rho, p).FV().NumPy().copy()
    assert np.max(np.abs(u2 - 0.25 * u1)) < 1e-9 * np.max(np.abs(u1))
    assert np.max(np.abs(u1)) > 0.0


@pytest.mark.parametrize("order", [1, 2])
def test_darcy_compliance_equals_twice_strain_energy(order):
    """Clapeyron: for linear elasticity without springs f(p)·u = uᵀKu = 2 SE."""
    from pacto_ng.responses import StrainEnergy

    mesh, dar, mech, rho = _pressure_mechanics(order)
    p = dar.forward(rho)
    u = mech.forward(rho, p)
    comp = Compliance(mech, dar).forward(u, p)
    se = StrainEnergy(mech).forward(u, rho, p)
    assert comp > 0
    assert abs(comp / (2 * se) - 1.0) < 1e-9


# -- bad input ----------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, field", [
    (dict(inlet="nowhere"), "inlet"),
    (dict(zero=("zero", "missing")), "zero"),
    (dict(zero="inlet"), "zero"),
    (dict(inlet=()), "inlet"),
    (dict(delta_s=0.0), "delta_s"),
    (dict(delta_s=-1e-3), "delta_s"),
    (dict(Ks=1.0), "Ks"),
    (dict(Ks=2.0), "Ks"),
    (dict(Ks=0.0), "Ks"),
    (dict(Ks=-1e-7), "Ks"),
    (dict(Kv=0.0, Ks=1e-9), "Kv"),
    (dict(r=0.0), "r"),
    (dict(r=1.0), "r"),
    (dict(r=2.0), "r"),
    (dict(beta_k=-1.0), "beta_k"),
    (dict(beta_h=-0.5), "beta_h"),
    (dict(eta_k=0.0), "eta_k"),
    (dict(eta_h=1.0), "eta_h"),
    (dict(eta_h=-0.2), "eta_h"),
    (dict(order=0), "order"),
])
def test_bad_input_raises_naming_the_field(kwargs, field):
    mesh = strip(0.01, 0.002, 5, 1)
    args = dict(inlet="inlet", zero="zero")
    args.update(kwargs)
    with pytest.raises(ValueError) as err:
        DarcyPressure(mesh, **args)
    msg = str(err.value)
    assert msg.startswith(f"{field}:") and "\n" not in msg
    if "nowhere" in str(kwargs) or "missing" in str(kwargs):
        assert "inlet" in msg and "zero" in msg and "free" in msg  # lists what exists


def test_wrong_density_length_and_unknown_body_field():
    from ngsolve import VectorH1, GridFunction

    mesh = strip(0.01, 0.002, 5, 1)
    block = DarcyPressure(mesh, inlet="inlet", zero="zero")
    with pytest.raises(ValueError, match="^rho_bar:"):
        block.forward(np.ones(mesh.ne + 1))
    u = GridFunction(VectorH1(mesh))
    with pytest.raises(ValueError, match="^p_name:"):
        darcy_body("pressure")(u, {"p": GridFunction(block.fes)})
