"""The descent loop of body-fitted shape refinement (pacto_ng/shape/riesz.py, refine.py).

Independent references:

* the Riesz field ``θ`` of a derivative ``g`` solves an SPD system on the free dofs, so
  ``g · θ = b(θ, θ) > 0`` and ``θ`` vanishes on the held dofs (and only the held component on
  a symmetry line);
* the Jacobian of the affine deformation ``d = (-x/2, y/4)`` of a straight-sided mesh is
  ``(1 - 1/2)(1 + 1/4) = 0.625`` at every point, whatever deformation the mesh is moved by
  when it is measured (the NGSolve notes' trap: with the deformation set, ``Grad`` is taken on
  the moved mesh);
* the step control is checked against the quality measure itself at the step it returns and
  at twice it;
* the refinement of the plate with a pressurised hole (the plate of test_shape_gradient.py,
  linear, fixed pressure, the mean x-displacement of the right edge as output) is checked for
  what any descent method must give: a larger output, a merit that decreases at every step,
  Jacobians above the bound and the volume bound met to a stated tolerance;
* the box bound: the order-1 VectorH1 dofs are the vertex displacements (component k of
  vertex i at dof k·nv + i, checked on an affine field), and the bounded refinement's vertices,
  read from the deformation field itself (not through that layout), lie in the box.

Not checked: a closed-form optimum.  The candidate (the pressurised thick ring of Lamé with a
free outer surface, maximising the outer radial displacement at fixed area) has no bounded
optimum among concentric rings (``u_r(b) ∝ a² b`` at fixed ``b² - a²`` grows without bound
as the ring grows), and the free shape need not stay concentric, so no prediction of the
moved material could be stated and checked honestly here.
"""
import math

import ngsolve as ng
import numpy as np
import pytest
from netgen.geom2d import unit_square
from ngsolve import CF, x, y

from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.shape import PartResponse, ShapeSpace, volume
from pacto_ng.shape.refine import STATUSES, refine
from pacto_ng.shape.riesz import Quality, RieszMap, step_length
from pacto_ng.threads import compute

from test_shape_gradient import A, B, params, plate, ring

#: one NGSolve thread, as in test_shape_gradient.py (small systems on a loaded 2-core machine)
THREADS = 1
Q_MIN = 0.3


def plate_response(mesh):
    return PartResponse(mesh, params=params("linear", 2, order=2), pressure=0.05,
                        supports=Supports(clamp=("left",)), ports=Port("right", (1.0, 0.0)))


@pytest.fixture
def plate_mesh():
    return plate()


# -- the Riesz map -----------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["elasticity", "laplace"])
def test_riesz_field_is_a_descent_direction_zero_on_held_dofs(plate_mesh, kind):
    """Clamp (every component held): θ is zero there, nonzero elsewhere, and g·θ > 0."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    response = plate_response(plate_mesh)
    with compute(THREADS):
        response.solve()
        g = response.gradient(space)
        theta = RieszMap(space, kind=kind)(g)
    assert np.all(theta[space.held] == 0.0) and np.any(space.held)
    assert np.count_nonzero(theta) > 0.5 * space.ndof
    assert float(g @ theta) > 0.0


def test_riesz_map_follows_the_moved_mesh(plate_mesh):
    """A second call after the mesh moved (the form reassembled, the factorisation updated)
    equals a fresh map's on the moved mesh, and differs from the first call's field."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    g = space.derivative(CF(1.0) * ng.dx(bonus_intorder=2))
    riesz = RieszMap(space)
    first = riesz(g)
    space.set(0.05 * space.direction(CF((x * y, x * x))))
    try:
        second, fresh = riesz(g), RieszMap(space)(g)
    finally:
        plate_mesh.UnsetDeformation()
    np.testing.assert_allclose(second, fresh, rtol=0, atol=1e-10 * np.max(np.abs(fresh)))
    assert np.max(np.abs(second - first)) > 1e-3 * np.max(np.abs(first))


def test_riesz_field_slides_on_symmetry_lines():
    """The quarter ring with symmetry lines (x fixed on ``left``, y on ``bottom``): the held
    component of θ is zero there, the other is not, and g·θ > 0 for the volume derivative."""
    mesh = ring(0.2, 1)
    space = ShapeSpace(mesh, hold=Supports(fix_x=("left",), fix_y=("bottom",)))
    g = space.derivative(CF(1.0) * ng.dx(bonus_intorder=2))
    theta = RieszMap(space, alpha=4.0)(g)
    assert float(g @ theta) > 0.0
    field = ng.GridFunction(space.space)
    field.vec.FV().NumPy()[:] = theta
    on_left = field(mesh(0.0, 0.5 * (A + B)))
    on_bottom = field(mesh(0.5 * (A + B), 0.0))
    assert abs(on_left[0]) < 1e-12 and abs(on_left[1]) > 1e-6
    assert abs(on_bottom[1]) < 1e-12 and abs(on_bottom[0]) > 1e-6


def test_riesz_field_with_extra_held_dofs(plate_mesh):
    """``hold`` (the active set of a box bound): θ zero on those dofs and the space's held
    ones, still g·θ > 0, and the space's own factorisation is left for the next call."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    g = space.derivative(CF(1.0) * ng.dx(bonus_intorder=2))
    riesz = RieszMap(space)
    plain = riesz(g)
    hold = np.zeros(space.ndof, dtype=bool)
    hold[np.flatnonzero(~space.held)[::3]] = True
    theta = riesz(g, hold=hold)
    assert np.all(theta[hold | space.held] == 0.0) and float(g @ theta) > 0.0
    assert np.max(np.abs(theta - plain)) > 1e-3 * np.max(np.abs(plain))
    np.testing.assert_allclose(riesz(g), plain, rtol=0, atol=1e-12 * np.max(np.abs(plain)))


def test_riesz_refuses_bad_settings(plate_mesh):
    space = ShapeSpace(plate_mesh, hold=("left",))
    with pytest.raises(ValueError, match="kind"):
        RieszMap(space, kind="h2")
    with pytest.raises(ValueError, match="alpha"):
        RieszMap(space, alpha=0.0)
    with pytest.raises(ValueError, match="entries"):
        RieszMap(space)(np.zeros(space.ndof + 1))


# -- the quality measure and the step control ------------------------------------------------
def test_quality_is_measured_on_the_reference_mesh():
    """det(I + ∇₀d) = 0.625 for d = (-x/2, y/4), measured at the reference and with the mesh
    already moved by d (the measure unsets and restores the deformation)."""
    mesh = ng.Mesh(unit_square.GenerateMesh(maxh=0.3))
    space = ShapeSpace(mesh)
    quality = Quality(space)
    d = space.direction(CF((-0.5 * x, 0.25 * y)))
    assert quality(d) == pytest.approx(0.625, rel=1e-12)
    space.set(d)
    try:
        assert quality(d) == pytest.approx(0.625, rel=1e-12)
        assert volume(mesh) == pytest.approx(0.625, rel=1e-12)  # the deformation stays set
    finally:
        mesh.UnsetDeformation()


def test_step_control_never_accepts_a_folded_mesh(plate_mesh):
    """A requested step of 10 (ten plate lengths along the unit-scaled descent field) is cut to
    one whose lowest Jacobian is ≥ q_min, and twice that step is below q_min (the largest of
    the halvings).  An unreachable bound gives the step 0."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    response = plate_response(plate_mesh)
    quality = Quality(space)
    with compute(THREADS):
        response.solve()
        theta = RieszMap(space)(response.gradient(space))
    theta /= np.max(np.abs(theta))
    zero = np.zeros(space.ndof)
    assert quality(10.0 * theta) < Q_MIN
    s, q = step_length(quality, zero, theta, 10.0, q_min=Q_MIN)
    print(f"step {s:.4g}, lowest det {q:.4f}, at twice the step {quality(2 * s * theta):.4f}")
    assert 0.0 < s < 10.0
    assert q >= Q_MIN and q == quality(s * theta)
    assert quality(2 * s * theta) < Q_MIN
    assert step_length(quality, zero, theta, 10.0, q_min=1.5) == (0.0, quality(zero))


# -- the refinement loop -----------------------------------------------------------------------
def test_refinement_increases_the_output_within_the_volume_bound(plate_mesh):
    """Five steps on the plate with the volume bound at 95 % of its start (so the constraint
    is violated at the start).  Measured: Δ 0.00865 → 0.0869 (5 accepted steps, one trial
    each), volume 0.08 % above the bound, lowest det 0.302."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    response = plate_response(plate_mesh)
    start = volume(plate_mesh, response.thickness)
    bound = 0.95 * start
    lines = []
    with compute(THREADS):
        result = refine(response, space, volume_max=bound, steps=5, step=0.02,
                        penalty=1000.0, q_min=Q_MIN, say=lines.append)
    history = result.history
    print("\n".join(lines))
    assert result.status in STATUSES and result.status == "steps"
    assert len(lines) == 5 == len(history) - 1
    assert history[0]["volume"] == pytest.approx(start, rel=1e-12)
    for before, after in zip(history, history[1:]):
        assert after["merit"] < after["merit_before"]  # monotone at the multiplier used
        assert after["delta"] > before["delta"]
        assert after["det"] >= Q_MIN and after["length"] > 0.0
    assert result.delta > 5.0 * history[0]["delta"]
    assert result.volume / bound - 1.0 <= 2e-3  # the bound met to 0.2 %
    assert result.volume < 0.99 * start
    np.testing.assert_array_equal(space.deformation.vec.FV().NumPy(), result.shape)
    assert result.delta == pytest.approx(response.delta, rel=1e-14)


def test_a_ratio_floor_pulls_the_mechanism_ratio_up(plate_mesh):
    """Five steps maximising Δ at the plate's own volume (μ = 10), without and with a floor
    on Δ/SE (``ratio_min``).  On this plate Δ/SE grows with Δ (measured: ×1.66 while Δ grows
    ×13.3), so a floor at the start's ratio never binds and changes nothing; a floor at
    twice it (violated at the start) is pulled towards: the ratio, measured afresh on the
    final shape by ``value("ratio")``, ends higher than without it (measured ×1.78) and Δ
    grows less (×9.2)."""
    results = {}
    for factor in (None, 1.0, 2.0):
        mesh = plate()
        space = ShapeSpace(mesh, hold=("left",))
        response = plate_response(mesh)
        with compute(THREADS):
            response.solve()
            start = response.value("ratio")
            result = refine(response, space, volume_max=volume(mesh, response.thickness),
                            ratio_min=None if factor is None else factor * start, steps=5,
                            step=0.02, penalty=10.0, q_min=Q_MIN)
            response.solve()
        results[factor] = (response.value("ratio") / start, result)
    (free, unheld), (same, inactive), (pulled, held) = (results[k] for k in (None, 1.0, 2.0))
    assert free > 1.0 and unheld.delta > 5.0 * unheld.history[0]["delta"]
    assert same == pytest.approx(free, rel=1e-9) and inactive.multipliers["ratio"] == 0.0
    assert pulled > free and held.multipliers["ratio"] > 0.0
    assert unheld.delta > held.delta > 2.0 * held.history[0]["delta"]
    assert all(math.isnan(h["ratio"]) for h in unheld.history)
    assert all(not math.isnan(h["ratio"]) for h in held.history)


def test_refinement_stops_when_the_quality_bound_cannot_be_met(plate_mesh):
    """With q_min 0.99 the first step the control allows is below min_step: the loop stops at
    once with the status ``mesh_quality`` and leaves the shape where it started."""
    space = ShapeSpace(plate_mesh, hold=("left",))
    response = plate_response(plate_mesh)
    with compute(THREADS):
        result = refine(response, space, volume_max=1.0, steps=3, step=0.02, q_min=0.9999,
                        min_step=1e-3)
    assert result.status == "mesh_quality"
    assert len(result.history) == 1 and not np.any(result.shape)
    assert math.isfinite(result.delta)


# -- the box bound -------------------------------------------------------------------------------
#: the plate's own bounding box
BOX = (np.array([0.0, 0.0]), np.array([1.0, 0.5]))


def moved_vertices(mesh, space):
    """The vertices moved by the space's deformation, evaluated from the field at the
    reference vertices (deformation unset), not through the dof layout."""
    ref = np.array([v.point for v in mesh.vertices], dtype=float)
    mesh.UnsetDeformation()
    try:
        motion = np.asarray(space.deformation(mesh(ref[:, 0], ref[:, 1])), dtype=float)
    finally:
        mesh.SetDeformation(space.deformation)
    return ref + motion.reshape(len(ref), -1)


def outside(points, box) -> float:
    return float(np.max(np.maximum(np.maximum(box[0] - points, points - box[1]), 0.0)))


def test_order_one_dofs_are_the_vertex_displacements():
    """The layout the box projection relies on: dof k·nv + i is component k of vertex i."""
    mesh = ng.Mesh(unit_square.GenerateMesh(maxh=0.3))
    space = ShapeSpace(mesh)
    d = space.direction(CF((x + 2 * y, 3 * x - y)))
    p = np.array([v.point for v in mesh.vertices])
    assert space.ndof == 2 * mesh.nv
    np.testing.assert_allclose(d[:mesh.nv], p[:, 0] + 2 * p[:, 1], rtol=0, atol=1e-14)
    np.testing.assert_allclose(d[mesh.nv:], 3 * p[:, 0] - p[:, 1], rtol=0, atol=1e-14)


def test_the_box_bound_keeps_the_part_in_and_the_output_grows():
    """Five steps at the plate's own volume.  Measured: unbounded, Δ 0.0086 → 0.0994 with a
    vertex 0.128 out of the plate's box; bounded by the box, Δ 0.0086 → 0.0311, every vertex
    in the box (1.1e-16), volume 3.7 % below the bound."""
    results = {}
    for bounds in (None, BOX):
        mesh = plate()
        space, response = ShapeSpace(mesh, hold=("left",)), plate_response(mesh)
        start = volume(mesh, response.thickness)
        with compute(THREADS):
            result = refine(response, space, volume_max=start, steps=5, step=0.02,
                            q_min=Q_MIN, bounds=bounds)
        results[bounds is not None] = result, outside(moved_vertices(mesh, space), BOX)
    (free, free_out), (boxed, boxed_out) = results[False], results[True]
    print(f"unbounded: Δ {free.delta:.4g}, {free_out:.3g} out; bounded: Δ {boxed.delta:.4g}, "
          f"{boxed_out:.3g} out")
    assert free_out > 0.05  # the unbounded refinement leaves the box
    assert boxed_out <= 1e-12
    assert boxed.status == "steps" and len(boxed.history) == 6
    assert boxed.delta > 2.0 * boxed.history[0]["delta"]
    for before, after in zip(boxed.history, boxed.history[1:]):
        assert after["merit"] < after["merit_before"] and after["det"] >= Q_MIN
        assert after["delta"] > before["delta"]


def test_the_box_bound_refuses_bad_boxes_and_higher_orders(plate_mesh):
    response = plate_response(plate_mesh)
    with pytest.raises(ValueError, match="coordinates"):
        refine(response, ShapeSpace(plate_mesh, hold=("left",)), volume_max=1.0, steps=0,
               bounds=((0.0, 0.0, 0.0), (1.0, 0.5, 1.0)))
    with pytest.raises(ValueError, match="order-1"):
        refine(response, ShapeSpace(plate_mesh, order=2, hold=("left",)), volume_max=1.0,
               steps=0, bounds=BOX)
