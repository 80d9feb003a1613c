"""The shape gradient of a part's output and volume (pacto_ng/shape/).

Independent references:

* central differences of the response under ``mesh.SetDeformation(±h V)`` for a random smooth
  ``V`` that vanishes on the held boundary: 2D and 3D, linear and Neo-Hookean, fixed and
  follower pressure (the derivative is of the discrete functional: O(h²) agreement);
* the volume: translating one face at unit speed changes the volume at the rate of the face's
  area (times the thickness in 2D), exactly for the discrete shape too (``∫ div V_h dx =
  ∫ V_h · n ds``, and the P1 field ``V_h``, e_x at the face's vertices and zero at the others,
  is the translation on that face, zero on the faces off it and tangent to the faces beside
  it);
* Lamé's thick-walled cylinder in plane strain (Timoshenko and Goodier 1970, *Theory of
  Elasticity*, 3rd ed., §28, eqs 200-202; the radial displacement under an internal pressure
  ``P`` and a free outer surface):

      u_r(r) = (1+ν) a² P / (E (b² - a²)) ((1-2ν) r + b²/r),

  whose derivative with respect to the inner radius ``a`` (the outer radius ``b`` fixed) is
  the shape derivative along a field ``V`` equal to the radial unit vector on the inner circle
  and zero on the outer one.  Two outputs: the inner radial displacement ``u_r(a)`` (a named
  point on the symmetry line, which moves with the inner circle) and the mean of ``u_r`` over
  the symmetry line ``a ≤ r ≤ b`` (a boundary that grows shorter as ``a`` grows),

      ū(a) = (1+ν) a² P / (E (b² - a²) (b - a)) ((1-2ν) (b² - a²)/2 + b² ln(b/a)).

  ``du_r(a)/da`` is differentiated by hand below; ``dū/da`` by a central difference of the
  closed formula (step 1e-5, truncation error ~1e-11 relative): neither uses the code.
"""
import math

import ngsolve as ng
import numpy as np
import pytest
from netgen import occ
from ngsolve import CF, cos, sin, sqrt, x, y, z

from pacto_ng.core import Chain
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port, Spring
from pacto_ng.physics.mechanics import Supports
from pacto_ng.shape import PartResponse, ShapeResponse, ShapeSpace, ShapeVolume
from pacto_ng.threads import compute
from rings import quarter_ring

E, NU = 1.0, 0.3
#: the systems here have at most a few thousand unknowns: one NGSolve thread (measured on the
#: loaded 2-core machine, the file took 3 s with one thread and 27 s with two)
THREADS = 1
#: Newton's residual tolerance of the finite-difference cases: the noise of Δ, divided by 2h
#: in the difference, stays far below the tolerance asserted
NEWTON_RTOL = 1e-12
STEP = 1e-4  # the central differences' step (the fields V are of size ~0.3)


def plate():
    """The plate [0, 1] x [0, 0.5] with a round hole (the ``pressure`` wall): edges left,
    right, free."""
    shape = occ.MoveTo(0, 0).Rectangle(1.0, 0.5).Face() - occ.Circle((0.45, 0.25), 0.12).Face()
    for e in shape.edges:
        c = e.center
        e.name = ("left" if abs(c.x) < 1e-9 else "right" if abs(c.x - 1) < 1e-9 else
                  "pressure" if math.hypot(c.x - 0.45, c.y - 0.25) < 0.2 else "free")
    mesh = ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=0.12))
    mesh.Curve(2)
    return mesh


def block():
    """The box [0, 1] x [0, 0.5]² with a box cavity (the ``pressure`` faces): faces left,
    right, free."""
    outer = occ.Box((0, 0, 0), (1.0, 0.5, 0.5))
    for f in outer.faces:
        c = f.center
        f.name = "left" if abs(c.x) < 1e-9 else "right" if abs(c.x - 1) < 1e-9 else "free"
    cavity = occ.Box((0.3, 0.15, 0.15), (0.6, 0.35, 0.35))
    cavity.faces.name = "pressure"
    return ng.Mesh(occ.OCCGeometry(outer - cavity).GenerateMesh(maxh=0.25))


@pytest.fixture(scope="module")
def meshes():
    return {2: plate(), 3: block()}


def params(model, dim, **kw):
    kw.setdefault("thickness", 0.1 if dim == 2 else 1e-3)
    return Parameters(model=model, E1=E, E0=1e-3 * E, E2=E, nu=NU, plane="strain", **kw)


def smooth_field(dim, seed):
    """A random smooth field, zero on x = 0 (the clamp), of size ~0.3."""
    c = np.random.default_rng(seed).uniform(-1.0, 1.0, 6)
    if dim == 2:
        return 0.3 * x * CF((c[0] * sin(3 * x + 1) + c[1] * cos(2 * y),
                             c[2] * cos(3 * y) + c[3] * sin(2 * x)))
    return 0.3 * x * CF((c[0] * sin(3 * x + 1) + c[1] * cos(2 * y) + z,
                         c[2] * cos(3 * y) + c[3] * sin(2 * z), c[4] * sin(2 * x + y) + c[5]))


# -- the output's gradient against central differences ---------------------------------------
@pytest.mark.parametrize("kind", ["fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean"])
@pytest.mark.parametrize("dim", [2, 3])
def test_gradient_matches_central_differences(meshes, dim, model, kind):
    """dΔ·V against (Δ(hV) - Δ(-hV)) / 2h, the response read through a Chain; held dofs have
    a zero gradient.  Measured relative errors (h = 1e-4, P2 displacement, P1 shape; 2D 88
    curved triangles, 3D 98 tetrahedra): 2D 1.3e-9 / 2.1e-9 (linear fixed /
    follower), 1.0e-9 / 1.3e-9 (Neo-Hookean, 4 Newton iterations); 3D 2.4e-8 / 1.3e-7,
    2.0e-8 / 3.0e-8."""
    mesh = meshes[dim]
    response = PartResponse(mesh, params=params(model, dim, order=2, newton_rtol=NEWTON_RTOL),
                            supports=Supports(clamp=("left",)), kind=kind, pressure=0.05,
                            ports=Port("right", (1.0,) + (0.0,) * (dim - 1)))
    space = ShapeSpace(mesh, hold=("left",))
    block_ = ShapeResponse(response, space)
    chain = Chain([block_], inputs=("shape",))
    V = space.direction(smooth_field(dim, seed=dim))
    zero = np.zeros(space.ndof)
    try:
        with compute(THREADS):
            chain.forward(shape=zero)
            grad = chain.gradient("delta", "shape")
            numeric = (block_.forward(STEP * V) - block_.forward(-STEP * V)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    analytic = float(grad @ V)
    rel = abs(analytic - numeric) / abs(numeric)
    print(f"{dim}D {model} {kind}: dΔ·V = {analytic:.10e}, FD {numeric:.10e}, rel {rel:.1e}")
    assert rel <= 1e-5
    assert np.all(grad[space.held] == 0.0) and np.any(space.held)
    assert np.count_nonzero(grad) > 0.5 * space.ndof


# -- the volume ----------------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_volume_gradient_is_the_translated_face_area(meshes, dim):
    """Translating the face x = 1 at unit speed (V = e_x at its vertices, zero at every other
    vertex): d(t|Ω|) = t · area(x = 1) exactly (2D: t 0.5, 3D: 0.5²), and the central
    difference."""
    mesh = meshes[dim]
    t = 0.1 if dim == 2 else 1.0
    space = ShapeSpace(mesh, hold=("left",))
    vol = ShapeVolume(space, thickness=t)
    V = space.direction(CF((1.0,) + (0.0,) * (dim - 1)), on="right")
    zero = np.zeros(space.ndof)
    try:
        vol.forward(zero)
        grad = vol.backward(1.0)[0]
        numeric = (vol.forward(STEP * V) - vol.forward(-STEP * V)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    area = t * 0.5 if dim == 2 else 0.25
    assert float(grad @ V) == pytest.approx(area, rel=1e-12)
    assert numeric == pytest.approx(area, rel=1e-9)


# -- Lamé's thick-walled cylinder ----------------------------------------------------------
A, B, P = 0.5, 1.0, 1e-3


def ring(maxh, order):
    """The quarter ring a <= r <= b (tests/rings.py), curved to ``order``."""
    return quarter_ring(A, B, maxh, order)


def lame_inner(a):
    """u_r(a) (the module)."""
    return (1 + NU) * a * a * P / (E * (B * B - a * a)) * ((1 - 2 * NU) * a + B * B / a)


def lame_inner_da(a):
    """d u_r(a)/da: u_r(a) = C N/D with C = (1+ν)P/E, N = (1-2ν)a³ + a b², D = b² - a²."""
    n, d = (1 - 2 * NU) * a**3 + a * B * B, B * B - a * a
    return (1 + NU) * P / E * ((3 * (1 - 2 * NU) * a * a + B * B) * d + 2 * a * n) / d**2


def lame_mean(a):
    """ū(a), the mean of u_r over a <= r <= b (the module)."""
    c = (1 + NU) * a * a * P / (E * (B * B - a * a) * (B - a))
    return c * ((1 - 2 * NU) * (B * B - a * a) / 2 + B * B * math.log(B / a))


def lame_errors(order):
    """Relative errors of (Δ, dΔ/da) against Lamé for the point and the mean output, on the
    ring of maxh 0.1 (122 triangles) at displacement, geometry and shape order ``order``."""
    mesh = ring(0.1, order)
    sym = Supports(fix_x=("left",), fix_y=("bottom",))
    space = ShapeSpace(mesh, order=order, hold=sym)  # the symmetry lines slide along themselves
    r = sqrt(x * x + y * y)
    V = space.direction(CF((x / r, y / r)) * (B - r) / (B - A))
    closed = {"inner": (lame_inner(A), lame_inner_da(A)),
              "bottom": (lame_mean(A), (lame_mean(A + 1e-5) - lame_mean(A - 1e-5)) / 2e-5)}
    out = {}
    for region, (value, slope) in closed.items():
        response = PartResponse(mesh, params=params("linear", 2, thickness=1.0), order=order,
                                supports=sym, ports=Port(region, (1.0, 0.0)), pressure=P)
        block_ = ShapeResponse(response, space)
        delta = block_.forward(np.zeros(space.ndof))
        grad = block_.backward(1.0)[0]
        out[region] = (delta / value - 1, float(grad @ V) / slope - 1)
    return out


def test_lame_cylinder_inner_radius_derivative():
    """The shape derivative along the inner radius against Lamé's closed form.  Measured
    (relative errors of Δ, dΔ/da):

    ========  ======================  ======================
    order     u_r(a) at the point     mean over a <= r <= b
    ========  ======================  ======================
    3         1.0e-5, 8.0e-5          1.2e-6, 2.4e-6
    4         2.2e-6, 3.4e-6          6.2e-8, 1.6e-7
    ========  ======================  ======================

    The derivative converges with the order as the output does (the discretisation error,
    not the gradient's: the central differences agree with it to 4e-8 on these meshes)."""
    with compute(THREADS):
        third, fourth = lame_errors(3), lame_errors(4)
    print(f"order 3: {third}\norder 4: {fourth}")
    bounds = {3: {"inner": (3e-5, 2e-4), "bottom": (4e-6, 8e-6)},
              4: {"inner": (6e-6, 1e-5), "bottom": (2e-7, 5e-7)}}
    for order, errors in ((3, third), (4, fourth)):
        for region, (value, slope) in errors.items():
            assert abs(value) <= bounds[order][region][0], (order, region, value)
            assert abs(slope) <= bounds[order][region][1], (order, region, slope)
    for region in ("inner", "bottom"):
        assert abs(fourth[region][1]) < 0.1 * abs(third[region][1])


# -- refused set-ups -------------------------------------------------------------------------
def test_refused_setups(meshes):
    mesh = meshes[2]
    good = dict(params=params("linear", 2), supports=Supports(clamp=("left",)), pressure=0.1,
                ports=Port("right", (1.0, 0.0)))
    with pytest.raises(ValueError, match="kind"):
        PartResponse(mesh, **good, kind="darcy")
    with pytest.raises(ValueError, match="neither"):
        PartResponse(mesh, **{**good, "ports": Port("nowhere", (1.0, 0.0))})
    with pytest.raises(ValueError, match="not a boundary"):
        ShapeSpace(mesh, hold=("nowhere",))
    space = ShapeSpace(mesh)
    with pytest.raises(ValueError, match="coefficients"):
        space.set(np.zeros(space.ndof + 1))


# -- an output spring on a boundary port -------------------------------------------------------
@pytest.mark.parametrize("kind", ["fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean"])
@pytest.mark.parametrize("dim", [2, 3])
def test_gradient_with_a_boundary_spring_matches_central_differences(meshes, dim, model, kind):
    """The output read on the ``right`` boundary with an output spring there (the runs'
    distributed spring, 1/|Γ| of the current shape), the boundary itself moved by the smooth
    field: dΔ·V against the central difference, and the spring acts (Δ smaller than without
    it).  Measured relative errors (h = 1e-4): 2D 1.1e-9 / 1.8e-9 (linear fixed / follower),
    1.5e-9 / 9.2e-10 (Neo-Hookean); 3D 9.2e-10 / 2.2e-8, 8.3e-10 / 8.2e-10; Δ 0.19-0.30 of its
    value without the spring.  Without the spring's explicit terms in L the errors are
    1.4e-2 to 4.3e-2 (checked once by leaving them out)."""
    mesh = meshes[dim]
    d = (1.0,) + (0.0,) * (dim - 1)
    space = ShapeSpace(mesh, hold=("left",))
    V = space.direction(smooth_field(dim, seed=dim + 10))
    k = 0.1 if dim == 2 else 1.0
    deltas, rel = spring_check(space, V, (0.0, k), lambda spring: PartResponse(
        mesh, params=params(model, dim, order=2, newton_rtol=NEWTON_RTOL),
        supports=Supports(clamp=("left",)), kind=kind, pressure=0.05,
        ports=Port("right", d, spring=spring)), f"boundary spring {dim}D {model} {kind}")
    assert 0.0 < deltas[k] < 0.9 * deltas[0.0]
    assert rel <= 1e-5


def radial_ring():
    """``(mesh, supports, space, V)``: the quarter ring (symmetry lines ``left`` and
    ``bottom``), its P1 shape space (as the refinement's) and the direction ``V`` that moves
    the inner radius out by 1 and the outer not at all."""
    mesh = ring(0.15, 2)
    sym = Supports(fix_x=("left",), fix_y=("bottom",))
    space = ShapeSpace(mesh, hold=sym)
    r = sqrt(x * x + y * y)
    return mesh, sym, space, space.direction(CF((x / r, y / r)) * (B - r) / (B - A))


def spring_check(space, V, stiffnesses, build, label: str):
    """``({k: Δ}, relative error)``: the response ``build(k)`` read through a ShapeResponse
    at each output-spring stiffness ``k``, and for the last one dΔ·V against the central
    difference (Δ(hV) - Δ(-hV)) / 2h."""
    deltas = {}
    try:
        with compute(THREADS):
            for k in stiffnesses:
                block_ = ShapeResponse(build(k), space)
                deltas[k] = block_.forward(np.zeros(space.ndof))
            grad = block_.backward(1.0)[0]
            numeric = (block_.forward(STEP * V) - block_.forward(-STEP * V)) / (2 * STEP)
    finally:
        space.mesh.UnsetDeformation()
    analytic = float(grad @ V)
    rel = abs(analytic - numeric) / abs(numeric)
    print(f"{label}: Δ {deltas}, dΔ·V = {analytic:.10e}, FD {numeric:.10e}, rel {rel:.1e}")
    return deltas, rel


# -- an output spring at a named point ---------------------------------------------------------
@pytest.mark.parametrize("spread", [0.0, 0.05])
@pytest.mark.parametrize("model, kind", [("linear", "fixed"), ("neohookean", "follower")])
def test_gradient_with_a_point_spring_matches_central_differences(model, kind, spread):
    """The quarter ring read at the point ``inner`` with an output spring there (the runs'
    set-up: pneunet's k_out): the spring's energy is in the state's residual and tangent, and
    its term has no explicit shape dependence, so dΔ·V agrees with the central difference
    along the inner radius field V; the spring holds the point back (Δ smaller than without
    it).  The stiffness is of the ring's own (E t = 1 N/m).  Measured (h = 1e-4, k = 0.1):
    relative error 1.5e-7 (linear, fixed) and 1.3e-7 (Neo-Hookean, follower), Δ 0.44 of its
    value without the spring; without the spring 4e-8 on this ring.  With k = 0.5 the
    derivative nearly cancels (dΔ·V ≈ -1e-5 against 3.5e-3 without) and the error is 1.4e-6
    with a P1 shape, 8.6e-5 with a P2 shape, whose central differences have a floor of ~6e-7
    even without the spring.

    ``spread`` 0.05 spreads the spring about the point over the boundary (a part's port
    spring, :class:`~pacto_ng.physics.loads.Spring`) and the shape holds its support, as the
    refinement does; V is the radius field with that support held.  Measured (h = 1e-4):
    relative error 2.6e-8 (linear, fixed), 2.5e-8 (Neo-Hookean, follower).  Without the hold
    (the weight moving with the boundary, its normalisation computed by another quadrature
    than the shape derivative's) 1e-2."""
    mesh, sym, space, V = radial_ring()
    if spread:
        spring = Spring("inner", 1.0, (1.0, 0.0), spread)
        space = ShapeSpace(mesh, hold=sym, near=(spring.support(mesh),))
        V = np.where(space.held, 0.0, V)
    pars = params(model, 2, thickness=1.0, newton_rtol=NEWTON_RTOL)
    deltas, rel = spring_check(space, V, (0.0, 0.1), lambda spring: PartResponse(
        mesh, params=pars, order=2, supports=sym, kind=kind,
        ports=Port("inner", (1.0, 0.0), spring=spring, spread=spread), pressure=P),
        f"spring {model} {kind} spread {spread}")
    assert 0.0 < deltas[0.1] < 0.9 * deltas[0.0]
    assert rel <= 1e-5
