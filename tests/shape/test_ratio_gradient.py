"""The strain energy of a part and the shape gradient of its mechanism ratio Δ/SE
(pacto_ng/shape/gradient.py).

Independent references:

* central differences of ``Δ/SE`` under ``mesh.SetDeformation(±h V)`` for a random smooth
  ``V`` that vanishes on the held boundary, as test_shape_gradient.py does for ``Δ`` (its
  meshes, fields and step): 2D and 3D, linear and Neo-Hookean, fixed and follower pressure
  (the derivative is of the discrete functional: O(h²) agreement);
* the strain energy of the linear model against ``½ u · K u``, ``K`` assembled here from
  Hooke's law (``σ = λ tr(ε) I + 2μ ε``, ``λ = Eν/((1+ν)(1-2ν))``, ``μ = E/(2(1+ν))``; plane
  strain in 2D, times the thickness), not from the code's energy;
* Clapeyron's theorem: in linear elasticity under a dead load the stored energy is half the
  work of the load (Love 1927, *A Treatise on the Mathematical Theory of Elasticity*, 4th ed.),
  here ``SE = ½ t ∫_Γp (-P N) · u ds`` with ``N`` the solid's outward normal on the cavity's
  wall, oriented by the test itself (the facet normal turned towards the cavity's centre).
  For the discrete state it holds exactly (``K u = f``, ``u · K u = f · u``).
"""
import ngsolve as ng
import numpy as np
import pytest
from ngsolve import (BND, CF, Grad, IfPos, InnerProduct, Integrate, Sym, Trace, specialcf, x,
                     y, z)

from pacto_ng.core import Chain
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.shape import PartResponse, ShapeResponse, ShapeSpace
from pacto_ng.threads import compute
from test_shape_gradient import (E, NEWTON_RTOL, NU, P, STEP, THREADS, block, params, plate,
                                 radial_ring, smooth_field)

PRESSURE = 0.05
#: the centres of the cavities of test_shape_gradient's plate (a round hole) and block (a box)
CENTRES = {2: (0.45, 0.25), 3: (0.45, 0.25, 0.25)}


@pytest.fixture(scope="module")
def meshes():
    return {2: plate(), 3: block()}


def response(mesh, model, kind, **kw):
    """The part clamped on ``left``, pressurised on ``pressure``, read on ``right`` along x."""
    dim = mesh.dim
    return PartResponse(mesh, params=params(model, dim, order=2, **kw),
                        supports=Supports(clamp=("left",)), kind=kind, pressure=PRESSURE,
                        ports=Port("right", (1.0,) + (0.0,) * (dim - 1)))


# -- the ratio's gradient against central differences ----------------------------------------
@pytest.mark.parametrize("kind", ["fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean"])
@pytest.mark.parametrize("dim", [2, 3])
def test_ratio_gradient_matches_central_differences(meshes, dim, model, kind):
    """d(Δ/SE)·V against (J(hV) - J(-hV)) / 2h, the ratio read through a Chain; held dofs
    have a zero gradient.  Measured relative errors (h = 1e-4, P2 displacement, P1 shape, the
    meshes of test_shape_gradient.py): 2D 1.6e-8 / 1.3e-8 (linear fixed / follower),
    1.4e-8 / 1.0e-8 (Neo-Hookean); 3D 1.1e-9 / 1.9e-8, 1.4e-9 / 3.4e-10.  In 2D they fall as
    h² (h = 1e-3: 1.5e-6, h = 1e-5: 1.4e-9, linear fixed)."""
    mesh = meshes[dim]
    part = response(mesh, model, kind, newton_rtol=NEWTON_RTOL)
    space = ShapeSpace(mesh, hold=("left",))
    block_ = ShapeResponse(part, space, objective="ratio")
    chain = Chain([block_], inputs=("shape",))
    V = space.direction(smooth_field(dim, seed=dim))
    zero = np.zeros(space.ndof)
    try:
        with compute(THREADS):
            chain.forward(shape=zero)
            ratio = part.delta / part.strain_energy
            grad = chain.gradient("ratio", "shape")
            numeric = (block_.forward(STEP * V) - block_.forward(-STEP * V)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    analytic = float(grad @ V)
    rel = abs(analytic - numeric) / abs(numeric)
    print(f"{dim}D {model} {kind}: Δ/SE = {ratio:.6e}, d(Δ/SE)·V = {analytic:.10e}, "
          f"FD {numeric:.10e}, rel {rel:.1e}")
    assert part.strain_energy > 0.0
    assert rel <= 1e-5
    assert np.all(grad[space.held] == 0.0) and np.any(space.held)
    assert np.count_nonzero(grad) > 0.5 * space.ndof


@pytest.mark.parametrize("model, kind", [("linear", "fixed"), ("neohookean", "follower")])
def test_ratio_gradient_with_a_point_spring_matches_central_differences(model, kind):
    """The quarter ring of test_shape_gradient.py read at the point ``inner`` with an output
    spring there (its energy in the residual, not in ``SE``), along the inner radius field.
    Measured relative errors (h = 1e-4, k = 0.1): 2.2e-8 (linear, fixed), 1.4e-8
    (Neo-Hookean, follower)."""
    mesh, sym, space, V = radial_ring()
    part = PartResponse(mesh, params=params(model, 2, thickness=1.0, newton_rtol=NEWTON_RTOL),
                        order=2, supports=sym, kind=kind, pressure=P,
                        ports=Port("inner", (1.0, 0.0), spring=0.1))
    block_ = ShapeResponse(part, space, objective="ratio")
    try:
        with compute(THREADS):
            block_.forward(np.zeros(space.ndof))
            analytic = float(block_.backward(1.0)[0] @ V)
            numeric = (block_.forward(STEP * V) - block_.forward(-STEP * V)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    rel = abs(analytic - numeric) / abs(numeric)
    print(f"spring {model} {kind}: d(Δ/SE)·V = {analytic:.10e}, FD {numeric:.10e}, rel {rel:.1e}")
    assert rel <= 1e-5


# -- the strain energy ---------------------------------------------------------------------
def hooke_stiffness(fes, thickness):
    """``K`` of ``t ∫ σ(u) : ε(v) dx`` (Hooke, plane strain in 2D), by the quadrature of the
    shape-differentiated forms (``bonus_intorder = 2``; on the curved 2D mesh the integrand is
    not a polynomial)."""
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = fes.TnT()
    eps_u, eps_v = Sym(Grad(u)), Sym(Grad(v))
    dim = fes.mesh.dim
    sigma = lam * Trace(eps_u) * ng.Id(dim) + 2 * mu * eps_u
    K = ng.BilinearForm(fes, symmetric=False)
    K += thickness * InnerProduct(sigma, eps_v) * ng.dx(bonus_intorder=2)
    return K.Assemble().mat


def pressure_work(mesh, u, thickness):
    """``t ∫_Γp (-P N) · u ds``, ``N`` the facet normal turned away from the solid (towards
    the cavity's centre)."""
    dim = mesh.dim
    n = specialcf.normal(dim)
    to_centre = CF(CENTRES[dim]) - CF((x, y, z)[:dim])
    N = IfPos(InnerProduct(n, to_centre), 1.0, -1.0) * n
    work = Integrate(-PRESSURE * thickness * InnerProduct(N, u), mesh, BND,
                     definedon=mesh.Boundaries("pressure"))
    return float(work)


@pytest.mark.parametrize("dim", [2, 3])
def test_linear_strain_energy_is_half_uKu_and_half_the_pressure_work(meshes, dim):
    """SE after the solve equals ½ u·K u and half the pressure's work, to 1e-10 relative.
    Measured relative differences (½ u·K u, ½ work): 2D plate 2e-16, 4e-15; 3D block 4e-16,
    4e-16.  (``Integrate`` of the energy density, with its own quadrature, is 1.3e-6 off on
    the curved plate: the check sees the quadrature.)"""
    mesh = meshes[dim]
    part = response(mesh, "linear", "fixed")
    with compute(THREADS):
        part.solve()
        K = hooke_stiffness(part.fes, part.thickness)
        half_uKu = 0.5 * InnerProduct(K * part.u.vec, part.u.vec)
        half_work = 0.5 * pressure_work(mesh, part.u, part.thickness)
    se = part.strain_energy
    print(f"{dim}D: SE {se:.12e}, ½ u·K u {half_uKu:.12e}, ½ work {half_work:.12e}")
    assert se > 0.0
    assert se == pytest.approx(half_uKu, rel=1e-10)
    assert se == pytest.approx(half_work, rel=1e-10)
    assert part.value("ratio") == pytest.approx(part.delta / half_uKu, rel=1e-10)
    assert part.value() == part.delta


def test_refused_objectives(meshes):
    mesh = meshes[2]
    part = response(mesh, "linear", "fixed")
    space = ShapeSpace(mesh, hold=("left",))
    with pytest.raises(ValueError, match="strained state"):
        part.value("ratio")  # no state yet
    with pytest.raises(ValueError, match="objective"):
        ShapeResponse(part, space, objective="energy")
    with compute(THREADS):
        part.solve()
        with pytest.raises(ValueError, match="objective"):
            part.gradient(space, objective="energy")


@pytest.mark.parametrize("kind", ["fixed", "follower"])
def test_a_weighted_gradient_is_the_weighted_sum(meshes, kind):
    """``gradient(space, {"delta": a, "ratio": b})`` (one adjoint and one shape derivative,
    as the refinement's step takes it) equals ``a dΔ + b d(Δ/SE)`` computed separately, to
    round-off: the adjoint right-hand side and the Lagrangian are linear in the weights."""
    mesh = meshes[2]
    part = response(mesh, "neohookean", kind)
    space = ShapeSpace(mesh, hold=("left",))
    a, b = 0.7, -3.0
    try:
        with compute(THREADS):
            part.solve()
            both = part.gradient(space, {"delta": a, "ratio": b})
            each = a * part.gradient(space, "delta") + b * part.gradient(space, "ratio")
    finally:
        mesh.UnsetDeformation()
    np.testing.assert_allclose(both, each, rtol=0, atol=1e-10 * np.max(np.abs(each)))
