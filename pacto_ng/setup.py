"""What a case puts on its mesh (:class:`Setup`, from the case's ``setup(params)``): supports,
loads, springs, output ports, passive regions, the Darcy pressure's boundaries
(:class:`Pressure`) and the objective, all by the geometry's names."""
from __future__ import annotations

from dataclasses import dataclass

from .errors import InputError
from .physics.loads import Outputs, PointLoad, Port, Spring
from .physics.mechanics import Supports

#: the objectives a case's set-up may name; :meth:`pacto_ng.builders.Builder.responses` builds
#: each one's blocks
OBJECTIVES = ("compliance", "energy", "output", "mechanism", "output_se")


@dataclass(frozen=True)
class Pressure:
    """Darcy pressure set-up: inlet and zero-pressure boundaries by name."""

    inlet: tuple[str, ...]
    zero: tuple[str, ...]


@dataclass(frozen=True)
class Setup:
    """What a case puts on its mesh (all region names refer to the layout's names)."""

    supports: Supports
    loads: tuple[PointLoad, ...] = ()
    springs: tuple[Spring, ...] = ()
    #: the output displacement Δ = d·u: a Port, or several (Δ = Σ weight d·u)
    port: Port | tuple[Port, ...] | None = None
    solid: tuple[str, ...] = ()  # passive solid materials
    void: tuple[str, ...] = ()  # passive void materials
    objective: str = "compliance"
    pressure: Pressure | None = None
    materials: int = 1
    se_max: float = 0.0  # strain-energy limit (J) of objective "output_se" unless --set se_max
    # typical magnitude of the objective; the run scales it to 10/objective_ref.  0: derived
    # for a pressure-driven mechanism (Case.derived_objective_ref), else the driver's
    # 10/|f0(x0)|, which fails for mechanisms whose initial design barely moves the output
    # (f0(x0) ≈ 0: the scaled objective then grows by 100x and MMA drops the volume
    # constraint for it)
    objective_ref: float = 0.0

    def __post_init__(self):
        if self.objective not in OBJECTIVES:
            raise InputError(f"objective: must be one of {', '.join(OBJECTIVES)} (got '{self.objective}')")
        if self.objective in ("output", "mechanism", "output_se") and not self.ports:
            raise InputError(f"objective '{self.objective}' needs an output port")
        for name in ("loads", "springs", "solid", "void"):
            if not isinstance(getattr(self, name), tuple):
                raise InputError(f"setup: {name} must be a tuple (got "
                                 f"{type(getattr(self, name)).__name__})")
        if not isinstance(self.supports, Supports):
            raise InputError(f"setup: supports must be a Supports (got "
                             f"{type(self.supports).__name__})")

    @property
    def ports(self) -> tuple[Port, ...]:
        """The output ports (none, one or several)."""
        if self.port is None:
            return ()
        return self.port if isinstance(self.port, tuple) else (self.port,)

    @property
    def output(self):
        """What the output displacement reads: the port, or :class:`Outputs` of several."""
        ports = self.ports
        return ports[0] if len(ports) == 1 else Outputs(ports)

    @property
    def all_springs(self) -> tuple[Spring, ...]:
        """The springs, and those the ports carry."""
        return self.springs + tuple(sp for port in self.ports for sp in port.springs())
