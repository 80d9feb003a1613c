"""The shape gradient of a part's output with its walls in self-contact
(pacto_ng/shape/contact_term.py) against central differences of the re-solved state, the
pairs sought anew at every shape.

The part: a block 1 x 1 m with a slot 0.02 m high open at its right end (from x = 0.3),
clamped on its left edge, a pressure on its top and bottom edges that squeezes the slot shut
(E = 1 MPa, ν = 0.3, plane strain; the walls meet at about 1 kPa: tests/physics/
test_contact.py), the output the top right corner's downward motion.  At 3 kPa the slot's
walls touch over its mouth (0.095 m), at 30 kPa over half the block (0.50 m); the direction
V moves every wall of the part, the slot's too.

The gradient holds the pairs' motion (ShapeContact.pair_motion: the contact residual's
derivative with the pairs sought anew, by central differences of the residual): measured
(2026-12-07, differences of the state at the step 1e-3) 2.2e-9 (linear), 6.0e-8
(Neo-Hookean), 1.2e-7 (Neo-Hookean at ν = 0.49, the mixed formulation) at 3 kPa, 4.4e-9 at
30 kPa; at the step 1e-4 the differences' own noise (Newton's tolerance over the step) is
2e-7.  Without the pairs'
motion (NGSolve's tangent, which holds the pairs) the error was 5.7e-4, 8.7e-5 and 1.5e-3 at
3 kPa, 6.2e-3 at first touch (1.1 kPa) and 0.12 at 30 kPa.  Without the contact's term at
all the error is 0.20 at 3 kPa (the term is a fifth of the derivative).  In 3D (the block
extruded 0.2 m, held in plane strain, tetrahedra of 0.1 m, order 1; slow): 5.1e-9, where
it was 2.6e-3."""
import numpy as np
import pytest
from ngsolve import (CF, BilinearForm, Grad, InnerProduct, VectorH1, cos, ds, dx, sin,
                     x, y, z)

from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.shape import PartResponse, ShapeSpace
from pacto_ng.shape.contact_term import MatrixSum, ShapeContact, column_colours
from pacto_ng.threads import compute
from contact_parts import slotted_block, slotted_slab

PRESSURE = 3e3
STEP = 1e-3  # the central differences' step (V is of size ~0.1)


def part(mesh, model, nu=0.3, pressure=PRESSURE):
    params = Parameters(model=model, E1=1e6, E0=1.0, E2=1e6, nu=nu, plane="strain",
                        thickness=1.0, order=2, newton_rtol=1e-10)
    return PartResponse(mesh, params=params, supports=Supports(clamp=("left",)),
                        pressure=pressure, kind="fixed", ports=Port("corner", (0.0, -1.0)))


def smooth_field(seed):
    """A random smooth field, zero on x = 0 (the clamp), of size ~0.1."""
    c = np.random.default_rng(seed).uniform(-1.0, 1.0, 4)
    return 0.1 * x * CF((c[0] * sin(3 * x + 1) + c[1] * cos(2 * y),
                         c[2] * cos(3 * y) + c[3] * sin(2 * x)))


def check(model, nu, pressure):
    """``(analytic, numeric, contact term, contact length)`` of dΔ·V on the slotted block."""
    mesh = slotted_block()
    response = part(mesh, model, nu, pressure)
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
    print(f"{model}, ν = {nu}, {pressure:g} Pa: Δ = {base:.6e}, contact length {area:.3e} m, "
          f"force {force:.3e} N/m, dΔ·V = {analytic:.10e}, FD {numeric:.10e}, "
          f"rel {abs(analytic - numeric) / abs(numeric):.1e}")
    assert area > 0.01 and force > 0.0  # the walls are in contact
    return analytic, numeric, term


@pytest.mark.parametrize("model, nu, pressure", [
    ("linear", 0.3, 3e3), ("neohookean", 0.3, 3e3), ("neohookean", 0.49, 3e3),
    ("linear", 0.3, 3e4)])
def test_the_gradient_with_the_walls_in_contact_matches_central_differences(model, nu,
                                                                            pressure):
    """At ν = 0.49 the part's state is the mixed formulation's (u, ϑ, p̃)."""
    analytic, numeric, term = check(model, nu, pressure)
    assert abs(analytic - numeric) / abs(numeric) < 1e-6
    assert abs(analytic + term - numeric) / abs(numeric) > 0.05  # the contact term matters


def test_without_the_pairs_motion_the_gradient_is_off_by_a_tenth(monkeypatch):
    """The same at 30 kPa with the pairs held in the adjoint and the shape term (NGSolve's
    contact tangent alone): 0.12 from the differences, measured (the contact pressure over
    the modulus, about 0.03, times the sliding the shape's motion brings)."""
    monkeypatch.setattr(ShapeContact, "pair_motion", lambda self, vec: None)
    analytic, numeric, _ = check("linear", 0.3, 3e4)
    assert abs(analytic - numeric) / abs(numeric) > 0.05


def test_no_row_meets_two_columns_of_one_colour():
    """The columns the pairs' motion differences at once (column_colours) on a random
    pattern: structurally orthogonal, and fewer colours than columns."""
    rng = np.random.default_rng(5)
    rows, cols = rng.integers(0, 200, 1500), rng.integers(0, 200, 1500)
    colour = column_colours(rows, cols)
    for c in np.unique(colour[cols]):
        at = colour[cols] == c
        pairs = set(zip(rows[at], cols[at]))
        row_of = {}
        for r, j in pairs:
            assert row_of.setdefault(r, j) == j  # one column of this colour per row
    assert len(np.unique(colour[cols])) < len(np.unique(cols))


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
    print(f"3D: dΔ·V = {analytic:.10e}, FD {numeric:.10e}, "
          f"rel {abs(analytic - numeric) / abs(numeric):.1e}")
    assert area > 1e-3 and force > 0.0
    assert abs(analytic - numeric) / abs(numeric) < 1e-6
    assert abs(analytic + term - numeric) / abs(numeric) > 0.1
