"""The body load as a design-independent coupling matrix (``Mechanics.assembly["body_coupling"]``).

A field the energy declares it does not read and that enters only through a body load linear
in it (the Darcy pressure) gives the load vector as ``B p`` and the adjoint term ``λᵀ ∂R/∂p``
as ``-s Bᵀλ``.  Checked against the routes they replace (the body load's LinearForm; the
symbolic derivative of ``λᵀ R``); a body that is not of that kind is refused with a clear error
unless it declares ``linear_in = None`` (the general route)."""
import numpy as np
import pytest

from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_body, darcy_follower
from pacto_ng.physics.loads import Spring
from pacto_ng.physics.materials import linear_energy, neohookean_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.traits import DeclarationError, declare
from pacto_ng.responses import StrainEnergy
from tests.small_cases import small_pa_mesh

SUP = Supports(clamp=("fixed",), fix_y=("symmetry",))


def _mech(kind="trig", order=1, *, body=None, energy=None, linear=True, follower=False):
    mesh = small_pa_mesh(kind)
    model = neohookean_energy if energy == "nh" else linear_energy
    energy = declare(lambda G, c: model(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4, "stress"),
                     reads=("rho_bar",), quadratic=model is linear_energy, stress_free=True)
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

    lag = mech.adjoint_lagrangian(mech.coeffs)
    lf = LinearForm(field.space)
    lf += lag.Diff(field.gf, field.space.TestFunction()) * mech.DX
    lf.Assemble()
    return lf.vec.FV().NumPy().copy()


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _body_load(mech):
    """``t ∫ b·v dΩ`` of the current fields as a LinearForm (the general route)."""
    from ngsolve import LinearForm

    lf = LinearForm(mech.fes)
    lf += mech.thickness * mech.body(mech.fes.TestFunction(), mech.coeffs) * mech.DX
    lf.Assemble()
    return lf.vec.FV().NumPy().copy()


def _random_states(mech, rng):
    mech.gfu.vec.FV().NumPy()[:] = np.where(mech.free, 1e-5 * rng.standard_normal(len(mech.free)), 0)
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0)


@pytest.mark.parametrize("kind,order,energy,linear", [
    ("trig", 1, "linear", True), ("quads", 2, "linear", True), ("trig", 2, "nh", False)])
def test_darcy_load_is_a_coupling_matrix(kind, order, energy, linear):
    """B p equals the body load's LinearForm and s Bᵀλ equals -∂(λᵀR)/∂p, for the linear
    and a nonlinear (Neo-Hookean) energy; the energy depends on ρ̄ and not on p."""
    mech, rng = _mech(kind, order, energy=energy, linear=linear)
    assert mech.energy_fields == {"rho_bar": True, "p": False}
    assert mech.assembly["body_coupling"] == ("p",)
    # the residual at u = 0 of a stress-free energy without point loads: minus the body load B p
    zero, r = mech.gfu.vec.CreateVector(), mech.gfu.vec.CreateVector()
    zero[:] = 0.0
    mech.residual(zero, r, 1.0)
    assert _rel(-r.FV().NumPy(), _body_load(mech)) <= 1e-13
    mech.load.Set(0.7)
    _random_states(mech, rng)
    sens = mech.field_sensitivity("p")  # s Bᵀλ
    ref = _reference_gradient(mech, mech.fields[1])
    assert _rel(sens, ref) <= 1e-12


def test_strain_energy_has_no_pressure_gradient():
    """The strain energy does not depend on p: its backward pass returns None for it."""
    mech, rng = _mech()
    se = StrainEnergy(mech)
    u = mech.gfu.vec.CreateVector()
    u.FV().NumPy()[:] = np.where(mech.free, 1e-5 * rng.standard_normal(len(mech.free)), 0)
    se.forward(u, None, None)
    g_u, g_rho, g_p = se.backward(1.0)
    assert g_p is None and np.all(np.isfinite(g_rho)) and np.max(np.abs(g_rho)) > 0


@pytest.mark.parametrize("make_body", [
    lambda: lambda u, c: c["rho_bar"] * darcy_body("p")(u, c),   # depends on ρ̄ as well
    lambda: lambda u, c: c["p"] * darcy_body("p")(u, c),         # not linear in p
])
def test_other_bodies_are_refused_unless_declared_general(make_body):
    """Taken (by default) as linear in p alone, these bodies fail the check with a clear error;
    declared ``linear_in = None`` they take the general route (FieldGradient), whose λᵀ∂R/∂p is
    the symbolic one."""
    with pytest.raises(DeclarationError, match="linear_in = None"):
        _mech(body=make_body(), linear=False)
    body = make_body()
    body.linear_in = None
    mech, rng = _mech(body=body, linear=False)
    assert mech.assembly["body_coupling"] == ()
    _random_states(mech, rng)
    assert _rel(mech.field_sensitivity("p"), _reference_gradient(mech, mech.fields[1])) <= 1e-12


def test_declared_coupling_field_is_used():
    """``body.linear_in = "p"`` declares the field explicitly (also with an undeclared
    energy, which may read every field)."""
    body = darcy_body("p")
    body.linear_in = "p"
    mech, rng = _mech(body=body)
    assert mech.assembly["body_coupling"] == ("p",)


def test_follower_load_keeps_the_general_route():
    """The follower load's residual density depends on p and u: no coupling shortcut, and
    λᵀ∂R/∂p is the symbolic derivative of λᵀR (residual density included)."""
    mech, rng = _mech(follower=True)
    assert mech.assembly["body_coupling"] == () and mech.has_residual_density
    _random_states(mech, rng)
    assert _rel(mech.field_sensitivity("p"), _reference_gradient(mech, mech.fields[1])) <= 1e-12
