"""The strain-energy density of a run's model: the material's energy (or the Wang
interpolation of it) with the SIMP modulus of the design field(s)."""
from __future__ import annotations


def make_energy(params: Parameters, penal, fields=("rho_bar",)):
    """Strain-energy density ``(G, coeffs) -> CF`` and the J-guard for the chosen model."""
    from ..interpolation import simp2_cf, simp2_np, simp_cf, simp_np
    from .materials import get_material, jacobian

    def modulus(c):
        if len(fields) == 2:
            return simp2_cf(c[fields[0]], c[fields[1]], params.E0, params.E1, params.E2, penal)
        return simp_cf(c[fields[0]], params.E0, params.E1, penal)

    if params.model == "wang":
        from . import wang

        gamma_fn = None
        if params.wang_gamma >= 0:  # a prescribed constant γ (identity checks, studies)
            from ngsolve import CF

            gamma_fn = lambda c: CF(params.wang_gamma)  # noqa: E731
        # the WangModel itself is the energy (callable), so γ and its measures stay reachable
        model = wang.wang_model(modulus, params.nu, params.plane, fields[0], penal,
                                beta=params.wang_beta, eta=params.wang_eta, gamma_fn=gamma_fn)
        return model, model.guard, False
    mat = get_material(params.model)

    def energy(G, c):
        return mat.energy(G, modulus(c), params.nu, params.plane)

    def modulus_np(values):
        """The modulus and its derivatives on the element values of the fields (numpy): the
        linear path's per-design coefficient (checked against the energy when the mechanics
        block is built, see physics.mechanics._LinearSystem)."""
        p = penal.Get()
        if len(fields) == 2:
            E, d1, d2 = simp2_np(values[fields[0]], values[fields[1]], params.E0, params.E1,
                                 params.E2, p)
            return E, {fields[0]: d1, fields[1]: d2}
        E, d = simp_np(values[fields[0]], params.E0, params.E1, p)
        return E, {fields[0]: d}

    energy.modulus_np = modulus_np
    guard = (lambda G, c: jacobian(G)) if mat.needs_positive_J else None
    return energy, guard, mat.linear
