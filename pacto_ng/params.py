"""Every parameter of a run, typed, with its unit and a one-line meaning, validated at
construction.  A case supplies its defaults; ``--set NAME=VALUE`` overrides any of them.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, fields


class InputError(ValueError):
    """Bad user input: the CLI prints the one-line message and exits with code 2."""


def _p(default, unit="", help=""):
    return field(default=default, metadata={"unit": unit, "help": help})


@dataclass(frozen=True)
class Parameters:
    # -- model and discretisation
    model: str = _p("linear", "", "mechanics: linear | gnl | neohookean | wang")
    order: int = _p(0, "", "element order of the displacement (1, 2, 3; 0: the case's order for the "
                    "model, see Case.model_orders)")
    maxh: float = _p(0.01, "m", "Netgen triangle size (used when nelx = 0)")
    nelx: int = _p(0, "", "structured quads in x (0: Netgen triangles)")
    nely: int = _p(0, "", "structured quads in y")
    plane: str = _p("strain", "", "strain | stress")
    thickness: float = _p(1e-3, "m", "out-of-plane thickness t")
    # -- materials
    E1: float = _p(3e9, "Pa", "Young's modulus of the solid (soft material with two materials)")
    E2: float = _p(3e9, "Pa", "Young's modulus of the stiff second material")
    E0: float = _p(3e3, "Pa", "Young's modulus of void")
    nu: float = _p(0.4, "", "Poisson's ratio")
    wang_beta: float = _p(100.0, "", "Wang interpolation sharpness β1")
    wang_eta: float = _p(0.001, "", "Wang interpolation threshold η1")
    wang_gamma: float = _p(-1.0, "", "Wang: a constant γ in [0, 1] instead of eq. 5.2 (-1: eq. 5.2)")
    # -- design
    volfrac: float = _p(0.2, "", "allowed volume fraction of the design domain")
    filter: str = _p("helmholtz", "", "helmholtz | cone | none")
    filter_radius: float = _p(0.0, "m", "filter radius R (0: 3 mesh sizes)")
    penal: float = _p(3.0, "", "SIMP penalty p (final value)")
    penal_start: float = _p(0.0, "", "penalty continuation start (0: none)")
    penal_step: float = _p(0.05, "", "penalty increment per penal_every iterations")
    penal_every: int = _p(1, "", "iterations between penalty increments")
    beta: float = _p(1.0, "", "projection sharpness β (start value; 0: no projection)")
    beta_max: float = _p(0.0, "", "final β of the doubling schedule (0: constant β)")
    beta_every: int = _p(10, "", "iterations between β doublings")
    eta: float = _p(0.5, "", "projection threshold η")
    # -- loads and ports
    load: float = _p(1.0, "N", "load magnitude (force in N, or inlet pressure in Pa)")
    load_width: float = _p(0.0, "m", "width of a spread force load: the cantilever's tip patch, the inverter's input (0: 4 and 2 element sizes, the cases' definitions)")
    output_width: float = _p(0.0, "m", "pa-inverter: the output spring and port spread over this length of the right edge from the output corner (0: the corner point, the case's definition)")
    load_ramp: int = _p(0, "", "iterations over which the load rises to full (0: none)")
    load_adapt: float = _p(1.2, "", "on a Newton failure go on at the load reached, raising it by this factor per iteration (0: stop at the failure)")
    k_in: float = _p(0.0, "N/m", "input spring stiffness")
    k_out: float = _p(0.0, "N/m", "output spring stiffness")
    # -- Darcy pressure (SPEC §2)
    Kv: float = _p(1.0, "m^2/(Pa s)", "flow coefficient of void")
    Ks: float = _p(1e-7, "m^2/(Pa s)", "flow coefficient of solid")
    eta_k: float = _p(0.3, "", "flow coefficient step threshold ηk")
    beta_k: float = _p(10.0, "", "flow coefficient step sharpness βk")
    eta_h: float = _p(0.2, "", "drainage step threshold ηh")
    beta_h: float = _p(10.0, "", "drainage step sharpness βh")
    r: float = _p(0.1, "", "pressure ratio reached at depth delta_s in solid")
    delta_s: float = _p(0.002, "m", "pressure penetration depth Δs")
    p_out: float = _p(0.0, "Pa", "drainage outside pressure")
    load_type: str = _p("fixed", "", "Darcy load: fixed | follower")
    follower_wang: bool = _p(True, "", "Wang model: the follower load sees I + γ∇u (void: fixed load)")
    load_sensitivity: bool = _p(True, "", "include the pressure-load sensitivity (off: study only)")
    volfrac2: float = _p(0.0, "", "volume fraction limit of the stiff material (0: none)")
    inlet: str = _p("", "", "Darcy inlet boundary name(s), '|'-separated (empty: the case's own)")
    se_max: float = _p(0.0, "J", "strain-energy limit of objective output_se (0: the case's default)")
    unit_elements: bool = _p(False, "", "structured mesh of unit square elements (domain nelx x nely)")
    # -- optimisation
    iterations: int = _p(100, "", "maximum optimisation iterations")
    optimizer: str = _p("mma", "", "mma | gcmma")
    move: float = _p(0.1, "", "move limit per iteration")
    tol: float = _p(0.01, "", "stop when the largest design change falls below this")
    obj_tol: float = _p(1e-4, "", "... or the objective changed less than this (relative) over 5 iterations")
    objective: str = _p("", "", "case objective variant (empty: the case's default)")
    seed_density: float = _p(0.0, "", "initial design density (0: volfrac)")
    init_design: str = _p("", "", "start from the design x of this run folder (its checkpoint.npz; "
                          "the same case and mesh), e.g. a run at a lower load")
    # -- Newton
    newton_rtol: float = _p(1e-10, "", "Newton residual tolerance (relative to the load)")
    newton_max_iter: int = _p(30, "", "Newton iterations per load step")
    newton_increment: float = _p(1.0, "", "first load increment of Newton continuation (fraction)")
    realcompile: bool = _p(False, "", "compile the Newton forms to machine code (C++ compiler; ~10-30 s once, 2.5-3.5x faster assembly)")
    newton_min_increment: float = _p(1.0 / 1024, "", "smallest load increment before Newton gives up (fraction)")

    def __post_init__(self):
        from .physics.materials import MODELS

        if self.model not in MODELS + ("auto",):
            raise InputError(f"model: unknown model '{self.model}' (choose from {', '.join(MODELS)})")
        if self.order not in (0, 1, 2, 3):
            raise InputError(f"order: must be 1, 2 or 3, or 0 for the case's choice (got {self.order})")
        if self.plane not in ("strain", "stress"):
            raise InputError(f"plane: must be 'strain' or 'stress' (got '{self.plane}')")
        if self.filter not in ("helmholtz", "cone", "none"):
            raise InputError(f"filter: must be helmholtz, cone or none (got '{self.filter}')")
        if self.optimizer not in ("mma", "gcmma"):
            raise InputError(f"optimizer: must be mma or gcmma (got '{self.optimizer}')")
        for name in ("E1", "E2", "E0", "thickness", "maxh", "penal"):
            if not getattr(self, name) > 0:
                raise InputError(f"{name}: must be positive (got {getattr(self, name)})")
        if not self.E0 < self.E1:
            raise InputError(f"E0: must be smaller than E1 (got {self.E0} >= {self.E1})")
        if not -1.0 < self.nu < 0.5:
            raise InputError(f"nu: Poisson's ratio must lie in (-1, 0.5) (got {self.nu})")
        if not 0.0 < self.volfrac < 1.0:
            raise InputError(f"volfrac: must lie in (0, 1) (got {self.volfrac})")
        if not 0.0 < self.eta < 1.0:
            raise InputError(f"eta: must lie in (0, 1) (got {self.eta})")
        if self.beta < 0 or self.beta_max < 0:
            raise InputError("beta: must be >= 0")
        if self.filter_radius < 0:
            raise InputError("filter_radius: must be >= 0")
        if self.nelx < 0 or self.nely < 0 or (self.nelx > 0) != (self.nely > 0):
            raise InputError("nelx, nely: give both (positive) or neither")
        if not 0 < self.move <= 1:
            raise InputError(f"move: must lie in (0, 1] (got {self.move})")
        if self.iterations < 0:
            raise InputError("iterations: must be >= 0")
        if self.k_in < 0 or self.k_out < 0:
            raise InputError("k_in, k_out: spring stiffnesses must be >= 0")
        if not 0 < self.newton_increment <= 1:
            raise InputError("newton_increment: must lie in (0, 1]")
        if not 0 < self.newton_min_increment <= self.newton_increment:
            raise InputError("newton_min_increment: must lie in (0, newton_increment]")
        if self.load_ramp < 0:
            raise InputError("load_ramp: must be >= 0")
        if self.load_adapt != 0 and not self.load_adapt > 1:
            raise InputError(f"load_adapt: must be 0 (off) or a growth factor > 1 (got {self.load_adapt})")
        if not 0.0 < self.r < 1.0:
            raise InputError(f"r: must lie in (0, 1) (got {self.r})")
        if self.load_width < 0:
            raise InputError(f"load_width: must be >= 0 (got {self.load_width})")
        if self.output_width < 0:
            raise InputError(f"output_width: must be >= 0 (got {self.output_width})")
        if not self.delta_s > 0:
            raise InputError(f"delta_s: must be positive (got {self.delta_s})")
        if not 0.0 < self.Ks < self.Kv:
            raise InputError(f"Ks: must satisfy 0 < Ks < Kv (got Ks={self.Ks}, Kv={self.Kv})")
        if self.wang_gamma != -1.0 and not 0.0 <= self.wang_gamma <= 1.0:
            raise InputError(f"wang_gamma: must be -1 (eq. 5.2) or lie in [0, 1] (got {self.wang_gamma:g})")
        if self.load_type not in ("fixed", "follower"):
            raise InputError(f"load_type: must be fixed or follower (got '{self.load_type}')")
        if not 0.0 <= self.volfrac2 < 1.0:
            raise InputError(f"volfrac2: must lie in [0, 1) (got {self.volfrac2})")
        if self.se_max < 0:
            raise InputError(f"se_max: must be >= 0 (got {self.se_max})")
        if self.unit_elements and self.nelx == 0:
            raise InputError("unit_elements: needs a structured mesh (give --nelx and --nely)")

    # -- helpers --------------------------------------------------------------------------
    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]

    def with_overrides(self, overrides: dict[str, str]) -> "Parameters":
        """Apply ``NAME=VALUE`` strings, converting to each field's type."""
        kinds = {f.name: f.type for f in fields(self)}
        changes = {}
        for name, text in overrides.items():
            if name not in kinds:
                raise InputError(f"--set: unknown parameter '{name}' (see --show-parameters)")
            cur = getattr(self, name)
            try:
                if isinstance(cur, bool):
                    val = text.lower() in ("1", "true", "yes", "on")
                elif isinstance(cur, int):
                    val = int(float(text))
                elif isinstance(cur, float):
                    val = float(text)
                else:
                    val = str(text)
            except ValueError:
                raise InputError(f"--set {name}: cannot read '{text}' as {type(cur).__name__}") from None
            changes[name] = val
        return dataclasses.replace(self, **changes)

    def describe(self, units: dict[str, str] | None = None) -> list[tuple[str, object, str, str]]:
        units = units or {}
        return [(f.name, getattr(self, f.name), units.get(f.name, f.metadata.get("unit", "")),
                 f.metadata.get("help", "")) for f in fields(self)]

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)
