"""The body load as a design-independent coupling matrix (``Mechanics._coupling``).

A field that enters only through a body load linear in it (the Darcy pressure) gives the load
vector as ``B p`` and the adjoint term ``λᵀ ∂R/∂p`` as ``-s Bᵀλ``.  Checked against the routes
they replace (the body load's LinearForm; the symbolic derivative of ``λᵀ R``), and that every
body that is not of that kind keeps the general route."""
import numpy as np
import pytest

from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure, darcy_body, darcy_follower
from pacto_ng.physics.loads import Spring
from pacto_ng.physics.materials import linear_energy, neohookean_energy
from pacto_ng.physics.mechanics import FieldGradient, Mechanics, Supports, _BodyCoupling
from pacto_ng.responses import StrainEnergy
from tests.small_cases import small_pa_mesh

SUP = Supports(clamp=("fixed",), fix_y=("symmetry",))


def _mech(kind="trig", order=1, *, body=None, energy=None, linear=True, follower=False):
    mesh = small_pa_mesh(kind)
    model = neohookean_energy if energy == "nh" else linear_energy
    energy = lambda G, c: model(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4, "stress")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=order)
    kw = dict(residual_density=darcy_follower("p")) if follower else dict(body=body or darcy_body("p"))
    mech = Mechanics(mesh, order=order, energy=energy, fields=["rho_bar", dar.field()],
                     supports=SUP, springs=(Spring("output", 1e4, (1.0, 0.0)),),
                     thickness=1e-3, linear=linear and not follower, **kw)
    rng = np.random.default_rng(11)
    rho = rng.uniform(0.05, 1.0, mesh.ne)
    mech.set_fields(rho, dar.forward(rho))
    return mech, rng


def _reference_gradient(mech, field):
    """∂(λᵀR)/∂field as the LinearForm of the symbolic derivative (no shortcut)."""
    from ngsolve import LinearForm

    lag = mech._adjoint_lagrangian(mech.coeffs)
    lf = LinearForm(field.space)
    lf += lag.Diff(field.gf, field.space.TestFunction()) * mech.DX
    lf.Assemble()
    return lf.vec.FV().NumPy().copy()


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("kind,order,energy,linear", [
    ("trig", 1, "linear", True), ("quads", 2, "linear", True), ("trig", 2, "nh", False)])
def test_darcy_load_is_a_coupling_matrix(kind, order, energy, linear):
    """B p equals the body load's LinearForm and s Bᵀλ equals -∂(λᵀR)/∂p, for the linear
    and a nonlinear (Neo-Hookean) energy; the energy depends on ρ̄ and not on p."""
    mech, rng = _mech(kind, order, energy=energy, linear=linear)
    assert mech._energy_fields == {"rho_bar": True, "p": False}
    c = mech._coupling
    assert isinstance(c, _BodyCoupling) and c.field.name == "p"
    assert mech._sens["p"] is c
    mech._fbody.Assemble()
    assert _rel(c.load().FV().NumPy(), mech._fbody.vec.FV().NumPy()) <= 1e-13
    mech.load.Set(0.7)
    mech.gfu.vec.FV().NumPy()[:] = np.where(mech.free, 1e-5 * rng.standard_normal(len(mech.free)), 0)
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0)
    out = c.field.gf.vec.CreateVector()
    c.adjoint_term(mech.lam.vec, mech.load.Get(), out)
    ref = _reference_gradient(mech, c.field)
    assert _rel(-out.FV().NumPy(), ref) <= 1e-12


def test_strain_energy_has_no_pressure_gradient():
    """The strain energy does not depend on p: its backward pass returns None for it."""
    mech, rng = _mech()
    se = StrainEnergy(mech)
    u = mech.gfu.vec.CreateVector()
    u.FV().NumPy()[:] = np.where(mech.free, 1e-5 * rng.standard_normal(len(mech.free)), 0)
    se.forward(u, None, None)
    g_u, g_rho, g_p = se.backward(1.0)
    assert g_p is None and np.all(np.isfinite(g_rho)) and np.max(np.abs(g_rho)) > 0


@pytest.mark.parametrize("body", [
    lambda u, c: c["rho_bar"] * darcy_body("p")(u, c),   # depends on ρ̄ as well
    lambda u, c: c["p"] * darcy_body("p")(u, c),         # not linear in p
])
def test_other_bodies_keep_the_general_route(body):
    mech, rng = _mech(body=body, linear=False)
    assert mech._coupling is None
    assert isinstance(mech._sens["p"], FieldGradient)


def test_follower_load_keeps_the_general_route():
    """The follower load's residual density depends on p and u: no coupling shortcut."""
    mech, _ = _mech(follower=True)
    assert mech._coupling is None
    assert isinstance(mech._sens["p"], FieldGradient)
