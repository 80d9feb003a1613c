"""The strain-energy density of a run's model: the material's energy (or the Wang
interpolation of it) with the SIMP modulus of the design field(s)."""
from __future__ import annotations

from dataclasses import dataclass

from ..params import InputError
from ..settings import Settings, setting


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


@dataclass(frozen=True)
class MaterialSettings(Settings):
    """The mechanics model and the material: moduli, Poisson's ratio, plane model, thickness,
    and the Wang interpolation's parameters."""

    model: str = setting("linear", "", "mechanics: linear | gnl | neohookean | wang | auto",
                         choices=("linear", "gnl", "neohookean", "wang", "auto"))
    plane: str = setting("strain", "", "strain | stress", choices=("strain", "stress"))
    thickness: float = setting(1e-3, "m", "out-of-plane thickness t", range="(0, inf)")
    E1: float = setting(3e9, "Pa", "Young's modulus of the solid (soft material with two "
                        "materials)", range="(0, inf)")
    E2: float = setting(3e9, "Pa", "Young's modulus of the stiff second material",
                        range="(0, inf)")
    E0: float = setting(3e3, "Pa", "Young's modulus of void", range="(0, inf)")
    nu: float = setting(0.4, "", "Poisson's ratio", range="(-1, 0.5)")
    wang_beta: float = setting(100.0, "", "Wang interpolation sharpness β1", range="(0, 1e6]")
    wang_eta: float = setting(0.001, "", "Wang interpolation threshold η1", range="(0, 1)")
    wang_gamma: float = setting(-1.0, "", "Wang: a constant γ in [0, 1] instead of eq. 5.2 "
                                "(-1: eq. 5.2)", range="[-1, 1]")

    def check(self):
        if not self.E0 < self.E1:
            raise InputError(f"E0: must be smaller than E1 (got {self.E0:g} >= {self.E1:g})")
        if self.wang_gamma != -1.0 and not 0.0 <= self.wang_gamma <= 1.0:
            raise InputError(f"wang_gamma: must be -1 (eq. 5.2) or lie in [0, 1] (got "
                             f"{self.wang_gamma:g})")
