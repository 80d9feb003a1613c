"""The strain-energy density of a run's model: the material's energy (or the Wang
interpolation of it) with the SIMP modulus of the design field(s), declaring what it is
(:class:`~pacto_ng.physics.traits.EnergyTraits`), from which the mechanics block picks its
assembly."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from ..errors import InputError
from ..interpolation import simp2_cf, simp2_np, simp_cf, simp_np
from ..settings import Settings, setting
from . import wang
from .hyperelastic import LAWS
from .materials import MODELS, get_material, jacobian
from .presets import PRESETS, fit_for, law_for
from .traits import declare

if TYPE_CHECKING:
    from ..params import Parameters


def make_energy(params: Parameters, penal, fields=("rho_bar",)):
    """Strain-energy density ``(G, coeffs) -> CF`` and the J-guard for the chosen model; the
    energy carries its :class:`~pacto_ng.physics.traits.EnergyTraits`.  The dimension is that
    of ``G`` (the mesh's): ``params.plane`` applies in 2D; in 3D ``plane=stress`` raises
    ``ValueError`` when the energy is evaluated (:func:`~pacto_ng.physics.gradient.dimension`)."""
    fields = tuple(fields)

    def modulus(c):
        if len(fields) == 2:
            return simp2_cf(c[fields[0]], c[fields[1]], params.E0, params.E1, params.E2, penal)
        return simp_cf(c[fields[0]], params.E0, params.E1, penal)

    law = _law(params)  # the rubber law and its shape (a preset's, or the default)
    if params.model == "wang":
        gamma_fn = None
        if params.wang_gamma >= 0:  # a prescribed constant γ (identity checks, studies)
            from ngsolve import CF

            gamma_fn = lambda c: CF(params.wang_gamma)  # noqa: E731
        # the WangModel itself is the energy (callable), so γ and its measures stay reachable;
        # φ_H is the preset's law if a preset is selected, else Neo-Hookean
        model = wang.wang_model(modulus, params.nu, params.plane, fields[0], penal,
                                beta=params.wang_beta, eta=params.wang_eta, gamma_fn=gamma_fn,
                                reads=fields, hyper=law if law is not None else "neohookean")
        return model, model.guard, False
    mat = get_material(params.model)
    if law is not None:
        mat = replace(mat, energy=law)

    def energy(G, c):
        return mat.energy(G, modulus(c), params.nu, params.plane)

    def modulus_np(values):
        """The modulus and its derivatives on the element values of the fields (numpy)."""
        p = penal.Get()
        if len(fields) == 2:
            E, d1, d2 = simp2_np(values[fields[0]], values[fields[1]], params.E0, params.E1,
                                 params.E2, p)
            return E, {fields[0]: d1, fields[1]: d2}
        E, d = simp_np(values[fields[0]], params.E0, params.E1, p)
        return E, {fields[0]: d}

    # the discrete energy is evaluated at the quadrature points only: the guard holds there
    # (docs/guide.md "Newton and failures", docs/studies.md "The Newton guard")
    declare(energy, reads=fields, quadratic=mat.linear, stress_free=mat.stress_free,
            modulus=modulus_np if mat.proportional_to_E else None, guard_points="quadrature")
    guard = (lambda G, c: jacobian(G)) if mat.needs_positive_J else None
    return energy, guard, mat.linear


def _law(params):
    """The :class:`~pacto_ng.physics.hyperelastic.Law` of the run's model with its shape (the
    preset's fit if ``material`` names one), or None (a model without one)."""
    return law_for(params.model, params.material)


#: what carries a load that a model's Newton cannot reach, said in the last line of a run that
#: stopped below its full load (measured: docs/studies.md "Extreme pressures at defaults")
WHEN_NEWTON_FAILS = {
    "neohookean": "--model wang carries such loads (Neo-Hookean where there is material, "
                  "linear in the void, whose crushed elements stop plain Neo-Hookean)",
}


@dataclass(frozen=True)
class MaterialSettings(Settings):
    """The mechanics model and the material: moduli, Poisson's ratio, plane model, thickness,
    and the Wang interpolation's parameters."""

    model: str = setting("linear", "", "mechanics: " + " | ".join(MODELS + ("auto",)),
                         choices=MODELS + ("auto",))
    plane: str = setting("strain", "", "strain | stress (2D meshes; a 3D mesh takes strain and "
                         "ignores it)", choices=("strain", "stress"))
    thickness: float = setting(1e-3, "m", "out-of-plane thickness t (2D meshes; a 3D mesh is "
                               "the body itself)", range="[1e-9, 1e9]")
    E1: float = setting(3e9, "Pa", "Young's modulus of the solid (soft material with two "
                        "materials)", range="[1e-12, 1e15]")
    E2: float = setting(3e9, "Pa", "Young's modulus of the stiff second material",
                        range="[1e-12, 1e15]")
    E0: float = setting(3e3, "Pa", "Young's modulus of void (at least 1e-12 E1)",
                        range="(0, 1e15]")
    nu: float = setting(0.4, "", "Poisson's ratio", range="(-1, 0.5)")
    wang_beta: float = setting(100.0, "", "Wang interpolation sharpness β1", range="(0, 1e6]")
    wang_eta: float = setting(0.001, "", "Wang interpolation threshold η1", range="(0, 1)")
    wang_gamma: float = setting(-1.0, "", "Wang: a constant γ in [0, 1] instead of eq. 5.2 "
                                "(-1: eq. 5.2)", range="[-1, 1]")
    material: str = setting("", "", "a material preset (physics/presets.py): the rubber law, its "
                            "coefficients and E1 = 2 μ0 (1 + ν), E0 scaled with E1, the preset's "
                            "ν unless nu is set ('': none)")
    nu_case: float = setting(0.4, "", "the ν the case set, recorded while material is '': a "
                             "preset replaces nu only while nu equals it", range="(-1, 0.5)")

    def __post_init__(self):
        self._apply_material()
        super().__post_init__()

    def _apply_material(self):
        """The preset's E1, E0 and ν (physics/presets.py, the rule); without a preset, record
        the case's ν in ``nu_case``."""
        if not self.material:
            object.__setattr__(self, "nu_case", self.nu)
            return
        preset = PRESETS.get(self.material)
        if preset is None:
            known = (f"known: {', '.join(PRESETS)}" if PRESETS else "none is registered: a case "
                     "file registers one with pacto_ng.physics.presets.register")
            raise InputError(f"material: unknown preset '{self.material}' ({known})")
        try:
            fit = fit_for(preset, self.model)
        except KeyError:
            raise InputError(f"model: material '{self.material}' has no {self.model} fit (it "
                             f"has {', '.join(preset.laws())})") from None
        nu = self.nu if self.nu != self.nu_case else preset.nu  # a --set nu= wins
        E1 = 2.0 * fit.mu0 * (1.0 + nu)
        object.__setattr__(self, "E0", self.E0 * (E1 / self.E1))  # the case's E0/E1 kept
        object.__setattr__(self, "E1", E1)
        object.__setattr__(self, "nu", nu)
        if self.model not in LAWS + ("linear", "gnl", "neohookean", "wang", "auto"):
            raise InputError(f"model: '{self.model}' cannot be used with material "
                             f"'{self.material}'")

    def check_explicit_E1(self, given: float):
        """Refuse an E1 given beside a material preset that sets another (the preset's
        E1 = 2 μ0 (1 + ν) would silently replace it): one line naming both."""
        if self.material and not math.isclose(float(given), self.E1, rel_tol=1e-12):
            raise InputError(f"E1: {float(given):g} Pa was given, but material "
                             f"'{self.material}' sets E1 = 2 μ0 (1 + ν) = {self.E1:.6g} Pa: "
                             "give one of them")

    def set_by_material(self) -> dict[str, str]:
        """``{name: how}`` of the values the material preset set (``--show-parameters``)."""
        if not self.material:
            return {}
        how = f"from material '{self.material}'"
        notes = {"E1": f"{how}: 2 μ0 (1 + ν)", "E0": f"{how}: the case's E0/E1 kept"}
        if self.nu == PRESETS[self.material].nu:
            notes["nu"] = f"{how}: its ν"
        return notes

    def check(self):
        if not self.E0 < self.E1:
            raise InputError(f"E0: must be smaller than E1 (got {self.E0:g} >= {self.E1:g})")
        if self.E0 < 1e-12 * self.E1:
            raise InputError(f"E0: must be at least 1e-12 E1 (got {self.E0:g} for E1 = "
                             f"{self.E1:g}): softer void makes the tangent singular in double "
                             "precision")
        if self.wang_gamma != -1.0 and not 0.0 <= self.wang_gamma <= 1.0:
            raise InputError(f"wang_gamma: must be -1 (eq. 5.2) or lie in [0, 1] (got "
                             f"{self.wang_gamma:g})")
