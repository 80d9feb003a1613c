"""The mixed displacement–pressure formulation (pacto_ng/physics/mixed.py): what it solves, that
it removes volumetric locking, and its adjoint.

References are independent of the code under test: a homogeneous deformation (where the
element mean of ``J`` is ``J`` itself, so the mixed and displacement formulations must agree
to round-off), the displacement formulation where it does not lock (ν = 0.3, fine mesh), and
central finite differences of the whole chain (:func:`pacto_ng.core.check_gradient`).
"""
from __future__ import annotations

import numpy as np
import pytest

from small_cases import chain_fd, pa_chain, small_pa_mesh
from pacto_ng.core import Chain
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
from pacto_ng.interpolation import simp_cf
from pacto_ng.mesh import Layout, Segment, netgen_mesh, structured_mesh
from pacto_ng.params import InputError, Parameters
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_body, darcy_follower
from pacto_ng.physics.loads import PointLoad, Port, Spring
from pacto_ng.physics.materials import jacobian, neohookean_energy, svk_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.mixed import formulation_for
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.wang import wang_model
from pacto_ng.responses import StrainEnergy, output_displacement

E1, E0 = 3e8, 3e2


def _model(name, nu):
    modulus = lambda c: simp_cf(c["rho_bar"], E0, E1, 3.0)
    if name in ("mooney_rivlin", "yeoh", "ogden"):  # the rubber laws as a run builds them
        from ngsolve import Parameter

        from pacto_ng.params import Parameters
        from pacto_ng.physics.energy import make_energy

        e, guard, _ = make_energy(Parameters(model=name, E1=E1, E0=E0, nu=nu), Parameter(3.0))
        return e, guard
    if name == "wang":
        return wang_model(modulus, nu, "strain", "rho_bar", 3.0)
    if name == "gnl":
        return (lambda G, c: svk_energy(G, modulus(c), nu)), None
    return (lambda G, c: neohookean_energy(G, modulus(c), nu)), (lambda G, c: jacobian(G))


# -- what it solves ------------------------------------------------------------------------------
def _stretched_block(formulation, order, kind):
    """A unit square in plane strain, x fixed on the left, y on the bottom, pulled on the right:
    a homogeneous state, Neo-Hookean at ν = 0.49."""
    lay = Layout(1.0, 1.0, segments=(Segment("left", (0, 0), (0, 1)),
                                     Segment("bottom", (0, 0), (1, 0)),
                                     Segment("right", (1, 0), (1, 1))))
    mesh = netgen_mesh(lay, 0.35) if kind == "trig" else structured_mesh(lay, 3, 3)
    energy = lambda G, c: neohookean_energy(G, 1e6, 0.49)
    mech = Mechanics(mesh, order=order, energy=energy, fields=(),
                     supports=Supports(fix_x=("left",), fix_y=("bottom",)),
                     loads=(PointLoad("right", (2e5, 0.0)),), thickness=1.0,
                     guard=lambda G, c: jacobian(G), newton=NewtonSettings(rtol=1e-12),
                     formulation=formulation)
    mech.forward()
    return mesh, mech


@pytest.mark.parametrize("kind, order", [("trig", 2), ("quad", 1)])
def test_homogeneous_state_equals_the_displacement_formulation(kind, order):
    """A homogeneous deformation has ``J`` constant, so the element mean of ``J`` is ``J`` and
    ``F̄ = F``: both formulations reach the same displacement (to round-off), and the element
    dilatation ``Θ`` equals ``J = F11 F22`` read from the displacement formulation."""
    mesh, disp = _stretched_block("displacement", order, kind)
    _, mixed = _stretched_block("mixed", order, kind)
    # (on triangles the mixed displacement space has the element bubble too: compare values)
    pts = [mesh(x, y) for x in np.linspace(0, 1, 7) for y in np.linspace(0, 1, 7)]
    ud = np.array([disp.gfu(p) for p in pts])
    um = np.array([mixed.gfu(p) for p in pts])
    assert np.max(np.abs(ud)) > 0.05  # a large stretch
    assert np.max(np.abs(um - ud)) < 1e-10 * np.max(np.abs(ud))
    # the dilatation is J of the homogeneous state, at every point
    _, theta, _ = mixed.components(mixed.gfx)
    F11 = 1.0 + disp.gfu(mesh(1.0, 0.5))[0]
    F22 = 1.0 + disp.gfu(mesh(0.5, 1.0))[1]
    assert np.allclose([1.0 + theta(p) for p in pts], F11 * F22, rtol=0, atol=1e-12)


@pytest.mark.parametrize("formulation", ["displacement", "mixed"])
def test_the_displacement_dofs_are_the_displacements(formulation):
    """``displacement_dofs`` picks the displacement's entries out of the state vector (the
    whole of it, or the mixed state's first component), the entries a path follower measures
    its lengths by: they are the displacement's own coefficients."""
    _, mech = _stretched_block(formulation, 2, "trig")
    state = mech.state_vector.FV().NumPy()[mech.displacement_dofs]
    assert np.array_equal(state, mech.u.vec.FV().NumPy())
    assert (mech.state_vector.size > state.size) == (formulation == "mixed")


def _cantilever(nu, formulation, n):
    """Tip deflection of a plane-strain Neo-Hookean cantilever (1 x 0.25 m, Q1 on 4n x n
    quads, a downward 20 N on the right edge: 4 % of the length) and its block."""
    lay = Layout(1.0, 0.25, segments=(Segment("fixed", (0.0, 0.0), (0.0, 0.25)),
                                      Segment("load", (1.0, 0.0), (1.0, 0.25))))
    mesh = structured_mesh(lay, 4 * n, n)
    mech = Mechanics(mesh, order=1, energy=lambda G, c: neohookean_energy(G, 1e6, nu),
                     fields=(), supports=Supports(clamp=("fixed",)),
                     loads=(PointLoad("load", (0.0, -20.0)),), thickness=0.1,
                     guard=lambda G, c: jacobian(G), newton=NewtonSettings(rtol=1e-10),
                     formulation=formulation)
    mech.forward()
    return -mech.gfu(mesh(1.0, 0.125))[1], mech


def test_mixed_removes_locking():
    """At ν = 0.4999 the displacement formulation (Q1, 32 x 8) locks: its tip deflection is a
    tenth of the reference; the mixed one (Q1/P0) is within 0.5 % of it.  The reference is the
    mixed formulation on the 4x finer mesh, checked at ν = 0.3 against the displacement
    formulation on that mesh (which does not lock there) to 0.5 %."""
    ref_03, _ = _cantilever(0.3, "mixed", 32)
    disp_03, _ = _cantilever(0.3, "displacement", 32)
    assert abs(ref_03 - disp_03) < 0.005 * ref_03
    ref, _ = _cantilever(0.4999, "mixed", 32)
    mixed, mech = _cantilever(0.4999, "mixed", 8)
    disp, _ = _cantilever(0.4999, "displacement", 8)
    print("tip deflection at nu = 0.4999: displacement", disp, "mixed", mixed, "reference", ref)
    assert abs(mixed - ref) < 0.005 * ref
    assert disp < 0.2 * ref  # locked
    assert mech.result.iterations <= 6


# -- the settings ----------------------------------------------------------------------------
def test_formulation_choice_and_refusals():
    kw = dict(model="neohookean", plane="strain", dim=2, order=2, simplices=True)
    assert formulation_for("auto", nu=0.4, **kw) == "displacement"
    assert formulation_for("auto", nu=0.49, **kw) == "mixed"
    assert formulation_for("auto", nu=0.49, **{**kw, "model": "linear"}) == "displacement"
    assert formulation_for("auto", nu=0.49, **{**kw, "order": 1}) == "displacement"
    assert formulation_for("auto", nu=0.49, **{**kw, "order": 1, "simplices": False}) == "mixed"
    assert formulation_for("auto", nu=0.49, **{**kw, "dim": 3}) == "displacement"  # tets
    assert formulation_for("auto", nu=0.49, **{**kw, "dim": 3, "simplices": False}) == "mixed"
    assert formulation_for("mixed", nu=0.3, **{**kw, "dim": 3}) == "mixed"
    assert formulation_for("displacement", nu=0.49, **kw) == "displacement"
    for bad in ({"model": "linear"}, {"plane": "stress"}, {"order": 1}):
        with pytest.raises(InputError, match="^formulation: "):
            formulation_for("mixed", nu=0.3, **{**kw, **bad})
    with pytest.raises(InputError, match="^formulation: "):
        formulation_for("both", nu=0.3, **kw)


# -- the adjoint -------------------------------------------------------------------------------
def _chain(kind, model, load_type, nu=0.49):
    mesh = small_pa_mesh(kind)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=2e5, order=1)
    energy, guard = _model(model, nu)
    load = dict(body=darcy_body("p")) if load_type == "fixed" else dict(
        residual_density=darcy_follower("p"))
    mech = Mechanics(mesh, order=2 if kind == "trig" else 1, energy=energy,
                     fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), thickness=1e-3, guard=guard,
                     newton=NewtonSettings(rtol=1e-12), formulation="mixed", **load)
    chain, x0 = pa_chain(mesh, dar, mech)
    return chain, mech, x0


@pytest.mark.parametrize("kind, model, load_type", [
    ("trig", "neohookean", "fixed"), ("trig", "neohookean", "follower"),
    ("quad", "gnl", "fixed"), ("quad", "wang", "follower"), ("trig", "yeoh", "follower"),
    ("quad", "mooney_rivlin", "follower"),
    # Ogden's spectral sums at F-bar: 443 s here (measured, a loaded machine): -m slow
    pytest.param("quad", "ogden", "fixed", marks=pytest.mark.slow)])
def test_mixed_chain_gradient(kind, model, load_type):
    """-Δ/SE, Δ and SE through the whole chain (filter, projection, Darcy, mixed mechanics with
    the element dilatation and pressure, responses) against the five-point central
    difference."""
    chain, mech, x0 = _chain(kind, model, load_type)
    chain.forward(x=x0)
    assert mech.formulation == "mixed" and mech.result.converged
    assert mech.result.iterations > 1
    errs = {name: chain_fd(chain, name, x0, h=1e-4, directions=2, stencil=4).rel_error
            for name in ("objective", "delta", "se")}
    print(kind, model, load_type, errs)
    assert max(errs.values()) < 1e-6, errs


# -- 3D ---------------------------------------------------------------------------------------
def _beam_3d(nu, formulation, n):
    """Tip deflection of a Neo-Hookean beam (1 x 0.25 x 0.25 m, Q1 on 4n x n x n hexahedra,
    clamped at x = 0, 5 N downward on the end face: 0.5 % of the length)."""
    from ngsolve.meshes import MakeStructured3DMesh

    mesh = MakeStructured3DMesh(hexes=True, nx=4 * n, ny=n, nz=n,
                                mapping=lambda x, y, z: (x, 0.25 * y, 0.25 * z))
    mech = Mechanics(mesh, order=1, energy=lambda G, c: neohookean_energy(G, 1e6, nu),
                     fields=(), supports=Supports(clamp=("back",)),
                     loads=(PointLoad("front", (0.0, -5.0, 0.0)),),
                     guard=lambda G, c: jacobian(G), newton=NewtonSettings(rtol=1e-10),
                     formulation=formulation)
    mech.forward()
    return -mech.gfu(mesh(1.0, 0.125, 0.125))[1]


def test_mixed_removes_locking_on_hexahedra():
    """ν = 0.4999: the displacement formulation on 16 x 4 x 4 hexahedra reaches a fifth of the
    reference (Q1/P0 on 32 x 8 x 8), the mixed one is within 2 % of it (measured 1.4 %)."""
    ref = _beam_3d(0.4999, "mixed", 8)
    mixed = _beam_3d(0.4999, "mixed", 4)
    disp = _beam_3d(0.4999, "displacement", 4)
    print("3D tip deflection: displacement", disp, "mixed", mixed, "reference", ref)
    assert abs(mixed - ref) < 0.02 * ref
    assert disp < 0.25 * ref


@pytest.mark.parametrize("kind, order, load", [("hex", 1, "follower"), ("tet", 2, "fixed")])
def test_mixed_chain_gradient_3d(kind, order, load):
    """The 3D chain (filter, projection, Darcy, mixed Neo-Hookean mechanics at ν = 0.49, strain
    energy and output displacement) against the five-point central difference."""
    from ngsolve import Parameter

    from pacto_ng.params import Parameters
    from pacto_ng.physics.energy import make_energy
    from pacto_ng.physics.mechanics import Field
    from test_3d_gradients import P_IN, mesh_of

    mesh, n = mesh_of(kind)
    field = DesignField(mesh)
    e, guard, _ = make_energy(Parameters(model="neohookean", E1=3e9, E0=3e3, nu=0.49),
                              Parameter(3.0))
    dar = DarcyPressure(mesh, inlet=n["inlet"], zero=n["zero"], p_in=P_IN, delta_s=0.1)
    extra = {"body": darcy_body("p")} if load == "fixed" else {
        "residual_density": darcy_follower("p")}
    port = Port(n["end"], (0.0, 1.0, 0.0), spring=1e6)
    mech = Mechanics(mesh, order=order, energy=e, fields=("rho_bar", Field("p", dar.fes)),
                     supports=Supports(clamp=(n["clamp"],)), guard=guard,
                     springs=port.springs(), newton=NewtonSettings(rtol=1e-12),
                     formulation="mixed", **extra)
    chain = Chain([Embed(field), HelmholtzFilter(mesh, 0.3), HeavisideProjection(2.0),
                   FixPassive(field), dar, mech, StrainEnergy(mech),
                   output_displacement(mech, port)])
    x0 = np.random.default_rng(2).uniform(0.3, 0.7, field.n)
    tip = float(chain.forward(x=x0)["delta"])
    assert mech.result.converged and abs(tip) > 0.02  # 2 % of the length
    errs = {name: chain_fd(chain, name, x0, h=1e-4, directions=2, stencil=4).rel_error
            for name in ("se", "delta")}
    print(kind, order, load, tip, errs)
    assert max(errs.values()) < 1e-6, errs


def test_iterative_route_equals_direct_with_condensation():
    """CG + BDDC on the condensed tangent (solvers.py: the harmonic extension and the local
    solves around the Krylov solve of the Schur complement) gives the direct route's state and
    adjoint sensitivities; Q2/P1 hexahedra, Neo-Hookean at ν = 0.49.  (At ν = 0.4999 CG with
    BDDC stalls near 1e-9 for the displacement formulation and the mixed one alike, measured:
    docs/guide.md "Nearly incompressible materials".)"""
    from ngsolve.meshes import MakeStructured3DMesh

    mesh = MakeStructured3DMesh(hexes=True, nx=8, ny=2, nz=2,
                                mapping=lambda x, y, z: (x, 0.25 * y, 0.25 * z))
    rho = np.random.default_rng(0).uniform(0.3, 1.0, mesh.ne)
    out = {}
    for solver in ("direct", "iterative"):
        mech = Mechanics(mesh, order=2, energy=lambda G, c: neohookean_energy(
                             G, 1e6 * (0.2 + c["rho_bar"]), 0.49),
                         supports=Supports(clamp=("back",)),
                         loads=(PointLoad("front", (0.0, -5.0, 0.0)),),
                         guard=lambda G, c: jacobian(G),
                         newton=NewtonSettings(rtol=1e-10, solver=solver), formulation="mixed")
        u = mech.forward(rho)
        g = u.CreateVector()
        g[:] = 0.0
        g.FV().NumPy()[:mech.fes.ndof] = np.random.default_rng(1).normal(size=mech.fes.ndof)
        out[solver] = (u.FV().NumPy().copy(), mech.backward(g)[0], mech.solver_info["kind"])
    assert out["iterative"][2] == "iterative" and out["direct"][2] == "direct"
    (ud, sd, _), (ui, si, _) = out["direct"], out["iterative"]
    assert np.max(np.abs(ui - ud)) < 1e-8 * np.max(np.abs(ud))
    assert np.max(np.abs(si - sd)) < 1e-8 * np.max(np.abs(sd))


def test_reanalysis_of_a_nearly_incompressible_ring_matches_lame():
    """The analysis of a part (pacto_ng/post/part_analysis.py) takes the mixed formulation by
    itself at ν = 0.4999 (order 2, triangles), and the quarter of a thick-walled cylinder
    (a = 1, b = 2, plane strain, P = 1e-5 E) then matches Lamé's
    ``u_r(a) = (1+ν) a² P / (E (b² - a²)) ((1-2ν) a + b²/a)`` to 1e-3 (measured 2.8e-4 on 75
    triangles; the Neo-Hookean departure from Lamé is about 0.6 P/E); the displacement
    formulation on the same mesh is 1.2 % stiff."""
    import ngsolve as ng
    from netgen import occ

    from pacto_ng.post.part_analysis import PartAnalysis

    E, nu, a, b = 1e6, 0.4999, 1.0, 2.0
    shape = (occ.Circle((0, 0), b).Face() - occ.Circle((0, 0), a).Face()) \
        * occ.MoveTo(0, 0).Rectangle(b, b).Face()
    for e in shape.edges:
        x, y = e.center.x, e.center.y
        e.name = ("left" if abs(x) < 1e-9 else "bottom" if abs(y) < 1e-9 else
                  "pressure" if np.hypot(x, y) < 0.5 * (a + b) else "outer")
    shape.vertices.Nearest((a, 0, 0)).name = "output"
    mesh = ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.25))
    mesh.Curve(3)
    P = 1e-5 * E
    lame = (1 + nu) * a * a * P / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a)
    params = Parameters(model="neohookean", E1=E, E0=1e-3 * E, nu=nu, thickness=1.0,
                        plane="strain")
    kw = dict(supports=Supports(fix_x=("left",), fix_y=("bottom",)),
              ports=Port("output", (1.0, 0.0)), order=2)
    auto = PartAnalysis(mesh, "fixed", params=params, **kw)
    assert auto.formulation == "mixed"
    mixed = auto.sweep([P]).delta[0]
    disp = PartAnalysis(mesh, "fixed", params=params.replace(formulation="displacement"),
                        **kw).sweep([P]).delta[0]
    print("Lamé", lame, "mixed", mixed / lame - 1, "displacement", disp / lame - 1)
    assert abs(mixed / lame - 1) < 1e-3
    assert disp / lame - 1 < -5e-3
