"""The shape gradient of a part's output with its walls in self-contact
(pacto_ng/shape/contact_term.py) against central differences of the re-solved state, the
pairs sought anew at every shape.

The part: a block 1 x 1 m with a slot 0.02 m high open at its right end (from x = 0.3),
clamped on its left edge, a pressure on its top and bottom edges that squeezes the slot shut
(E = 1 MPa, ν = 0.3, plane strain; the walls meet at about 1 kPa: tests/physics/
test_contact.py), the output the top right corner's downward motion.  At 3 kPa the slot's
walls touch over its mouth; the direction V moves every wall of the part, the slot's too.

The gradient is not exact: NGSolve's contact tangent holds the pairs (and the contact
normals) where the last pairing put them, and so do the adjoint and the shape term built on
it, while the re-solved states of the differences pair anew.  Measured (2026-12-06): relative
errors 5.7e-4 (linear), 8.7e-5 (Neo-Hookean) and 1.5e-3 (Neo-Hookean at ν = 0.49, the mixed
formulation), the same for steps from 1e-3 to 1e-5
(5.70e-4, 5.70e-4, 5.70e-4, 5.70e-4, 5.71e-4: not the differences' own error); without the
contact term the error is 0.20 (the term is a fifth of the derivative).  Newton's pairings
converge linearly for the same reason (the residual after each pairing falls by about 10x).
The test asserts 1e-3 (2e-3 at ν = 0.49): the contact term right to 0.3 % (0.7 %) of itself.
With the pairs held in the differences the gradient is exact (to 1e-7, measured 1e-10 to 6e-9:
test_with_the_pairs_held_the_gradient_is_exact).  In 3D (the block extruded
0.2 m, held in plane strain, tetrahedra of 0.1 m; slow): 2.6e-3 at order 1 (20 s) and 3.1e-3
at order 2 (106 s), without the contact term 0.21 and 0.20: the term right to 1.3-1.6 % of
itself; the test asserts 5e-3 at order 1."""
import numpy as np
import pytest
from ngsolve import (CF, BilinearForm, Grad, InnerProduct, VectorH1, cos, ds, dx, sin,
                     x, y, z)

from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.shape import PartResponse, ShapeSpace
from pacto_ng.shape.contact_term import MatrixSum, ShapeContact
from pacto_ng.threads import compute
from contact_parts import slotted_block, slotted_slab

PRESSURE = 3e3
STEP = 1e-4  # the central differences' step (V is of size ~0.1)


def part(mesh, model, nu=0.3):
    params = Parameters(model=model, E1=1e6, E0=1.0, E2=1e6, nu=nu, plane="strain",
                        thickness=1.0, order=2, newton_rtol=1e-10)
    return PartResponse(mesh, params=params, supports=Supports(clamp=("left",)),
                        pressure=PRESSURE, kind="fixed", ports=Port("corner", (0.0, -1.0)))


def smooth_field(seed):
    """A random smooth field, zero on x = 0 (the clamp), of size ~0.1."""
    c = np.random.default_rng(seed).uniform(-1.0, 1.0, 4)
    return 0.1 * x * CF((c[0] * sin(3 * x + 1) + c[1] * cos(2 * y),
                         c[2] * cos(3 * y) + c[3] * sin(2 * x)))


@pytest.mark.parametrize("model, nu, tol", [("linear", 0.3, 1e-3), ("neohookean", 0.3, 1e-3),
                                            ("neohookean", 0.49, 2e-3)])
def test_the_gradient_with_the_walls_in_contact_matches_central_differences(model, nu, tol):
    """At ν = 0.49 the part's state is the mixed formulation's (u, ϑ, p̃): measured 1.5e-3,
    the contact term a fifth of the derivative as at ν = 0.3 (0.22 without it)."""
    mesh = slotted_block()
    response = part(mesh, model, nu)
    assert response.formulation == ("mixed" if nu > 0.45 else "displacement")
    space = ShapeSpace(mesh, hold=("left",))
    response.use_contact(space, ("slot",))
    V = space.direction(smooth_field(seed=7))

    def output(t):
        space.set(t * V)
        return response.solve()

    try:
        with compute(1):
            base = output(0.0)
            area, force, _ = response.contact.measure(response.u.vec)
            gradient = response.gradient(space)
            term = float(response.contact.shape_term(response.adjoint_state.vec) @ V)
            analytic = float(gradient @ V)
            numeric = (output(STEP) - output(-STEP)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    rel = abs(analytic - numeric) / abs(numeric)
    print(f"{model}, ν = {nu}: Δ = {base:.6e}, contact length {area:.3e} m, force {force:.3e} N/m, "
          f"dΔ·V = {analytic:.10e}, FD {numeric:.10e}, rel {rel:.1e}")
    assert area > 0.01 and force > 0.0  # the walls are in contact
    assert rel < tol
    assert abs(analytic + term - numeric) / abs(numeric) > 0.1  # the contact term matters


@pytest.mark.parametrize("model, nu", [("linear", 0.3), ("neohookean", 0.3),
                                       ("neohookean", 0.49)])
def test_with_the_pairs_held_the_gradient_is_exact(model, nu, monkeypatch):
    """Where the gradient's error comes from: the same part, the differences re-solved with
    the contact's pairs (and normals) held where the base state's pairing put them, the
    discrete problem the adjoint and the shape term differentiate.  They match to 1e-7
    (measured 2026-12-07 at the step 1e-4: 1.2e-10, 1.3e-10 and 6.3e-9; at 1e-3 1.1e-8 in
    all three, the differences' own error), so the 5.7e-4 to 1.5e-3 of the test above is
    the pairs' motion alone, which NGSolve's contact tangent leaves out."""
    mesh = slotted_block()
    response = part(mesh, model, nu)
    space = ShapeSpace(mesh, hold=("left",))
    response.use_contact(space, ("slot",))
    V = space.direction(smooth_field(seed=7))

    def output(t):
        space.set(t * V)
        return response.solve()

    try:
        with compute(1):
            output(0.0)
            analytic = float(response.gradient(space) @ V)
            monkeypatch.setattr(ShapeContact, "pair", lambda self, vec: None)
            numeric = (output(STEP) - output(-STEP)) / (2 * STEP)
            area, force, _ = response.contact.measure(response.u.vec)
    finally:
        mesh.UnsetDeformation()
    assert area > 0.01 and force > 0.0  # the walls are in contact at the shifted shape too
    assert abs(analytic - numeric) / abs(numeric) < 1e-7


def test_the_sum_of_two_patterns_is_their_matrices_sum():
    """MatrixSum: a + b on the union of two sparsity patterns (the body's volume couplings,
    a boundary term's), made once and then summed anew, against the two products."""
    mesh = slotted_block(0.2)
    space = VectorH1(mesh, order=2, dirichlet="left")
    u, v = space.TnT()
    a = BilinearForm(space, symmetric=False)
    a += InnerProduct(Grad(u), Grad(v)) * dx
    b = BilinearForm(space, symmetric=False)
    b += (x + 2) * InnerProduct(u, v) * ds("slot")
    total = MatrixSum()
    vec = None
    for scale, new in ((1.0, True), (3.0, False)):  # the pattern made, then reused
        a.Assemble()
        b.Assemble()
        b.mat.AsVector().data *= scale
        if vec is None:
            vec = a.mat.CreateColVector()
            vec.FV().NumPy()[:] = np.random.default_rng(3).random(len(vec))
        assert total.of(a.mat, b.mat) is new
        got, want, extra = (vec.CreateVector() for _ in range(3))
        got.data = total.matrix * vec
        want.data = a.mat * vec
        extra.data = b.mat * vec
        want.data += extra
        assert np.abs(got.FV().NumPy() - want.FV().NumPy()).max() <= \
            1e-13 * np.abs(want.FV().NumPy()).max()


@pytest.mark.slow
def test_the_gradient_with_the_walls_in_contact_in_3d():
    mesh = slotted_slab()
    held = Supports(clamp=("left",), fix_z=("front", "back"))
    params = Parameters(model="linear", E1=1e6, E0=1.0, E2=1e6, nu=0.3, order=1,
                        newton_rtol=1e-10)
    response = PartResponse(mesh, params=params, supports=held, pressure=PRESSURE,
                            kind="fixed", ports=Port("corner", (0.0, -1.0, 0.0)))
    space = ShapeSpace(mesh, hold=held)
    response.use_contact(space, ("slot",))
    c = np.random.default_rng(7).uniform(-1.0, 1.0, 4)
    V = space.direction(0.1 * x * CF((c[0] * sin(3 * x + 1) + c[1] * cos(2 * y),
                                      c[2] * cos(3 * y) + c[3] * sin(2 * x), 0 * z)))

    def output(t):
        space.set(t * V)
        return response.solve()

    try:
        with compute(1):
            output(0.0)
            area, force, _ = response.contact.measure(response.u.vec)
            gradient = response.gradient(space)
            term = float(response.contact.shape_term(response.lam.vec) @ V)
            numeric = (output(STEP) - output(-STEP)) / (2 * STEP)
    finally:
        mesh.UnsetDeformation()
    analytic = float(gradient @ V)
    assert area > 1e-3 and force > 0.0
    assert abs(analytic - numeric) / abs(numeric) < 5e-3
    assert abs(analytic + term - numeric) / abs(numeric) > 0.1
