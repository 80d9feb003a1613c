"""The problem a case's chain builds (:meth:`pacto_ng.builders.Builder.problem`): the mesh, the
design field, the chain of blocks, the objective and the constraints, and what the optimiser
asks of them (schedules, evaluations, the reported design)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

import numpy as np

from .parallel import total

if TYPE_CHECKING:
    from .case import Case
    from .core import Chain
    from .params import Parameters
    from .setup import Setup


def shown_density(values: dict) -> np.ndarray:
    """The element densities that show a design, of its ``values`` (element arrays by name):
    ρ̄, or with two materials ρ̄1 (1 + ρ̄2) / 2 (void 0, the soft material 1/2, the stiff
    material 1)."""
    if "rho_bar" in values:
        return np.asarray(values["rho_bar"])
    return np.asarray(values["rho_bar1"]) * (1 + np.asarray(values["rho_bar2"])) / 2.0


@dataclass
class Problem:
    """A built optimisation problem: mesh, design field, chain and response names."""

    case: Case
    params: Parameters
    mesh: object
    field: object
    chain: Chain
    objective: str
    constraints: list[str]
    mech: object
    projections: list
    penal: object  # ngsolve Parameter
    setup: Setup
    h: float
    reports: list[str] = field(default_factory=list)  # scalar values to log each iteration
    pressure_block: object = None
    n_design_fields: int = 1
    model_choice: dict | None = None  # what --model auto decided, and why
    load_ramp_choice: dict | None = None  # what load_ramp=-1 decided, and why
    #: the netgen.occ shape the mesh was made from (None: a mesh file or structured quads)
    shape: object = None
    #: a worst-case objective (:mod:`pacto_ng.robust`): the names of the terms whose maximum
    #: is the objective (the optimiser takes them one by one); empty: the objective itself
    objective_terms: tuple = ()
    #: further mechanics blocks of the chain (the robust realisations), under the same load
    extra_mechanics: list = field(default_factory=list)
    #: ``f(k, history)`` called at the start of iteration k (the robust formulation's volume
    #: target), or None
    before_iteration: Callable | None = None
    #: on a distributed mesh (:func:`pacto_ng.parallel.distribute`) where the local elements
    #: sit in the serial order; None on a serial mesh
    numbering: object = None
    #: and where its design variables sit in the serial design vector
    #: (:class:`pacto_ng.parallel.DesignNumbering`); None on a serial mesh
    design_numbering: object = None

    @property
    def mechanics(self) -> list:
        """Every mechanics block: :attr:`mech`, then :attr:`extra_mechanics`."""
        return [self.mech] + list(self.extra_mechanics)

    # -- schedules ----------------------------------------------------------------------------
    def schedule_now(self) -> tuple[float, float, float]:
        """The penalty, β and load factor applied now (:meth:`apply_schedule`'s arguments)."""
        beta = self.projections[0].beta if self.projections else 1.0
        return self.penal.Get(), float(beta), float(self.mech.target)

    def apply_schedule(self, penal: float, beta: float, load: float) -> None:
        self.penal.Set(penal)
        for pr in self.projections:
            pr.beta = beta
        for mech in self.mechanics:
            mech.target = load

    def expect_many_designs(self) -> None:
        """An optimisation follows: every block that assembles per design (mechanics, Darcy
        pressure; the robust realisations' too) takes the optimisation's route from the
        process's first design on, so a resumed run repeats the uninterrupted one bit for
        bit."""
        for block in self.chain.blocks:
            if callable(getattr(block, "expect_many_designs", None)):
                block.expect_many_designs()

    @property
    def warm(self) -> list:
        """Where every mechanics block's next forward pass starts (:attr:`mech`, then
        :attr:`extra_mechanics`): their warm states and Newton results, for :meth:`set_warm`."""
        return [(m.state, m.result) for m in self.mechanics]

    def set_warm(self, warm: list) -> None:
        """Start the next forward passes from ``warm`` (:attr:`warm` of earlier)."""
        for m, (state, result) in zip(self.mechanics, warm):
            m.set_state(state, result=result)

    def start_iteration(self, k: int, history: list) -> None:
        """What changes with the iteration besides the schedules (:attr:`before_iteration`)."""
        if self.before_iteration is not None:
            self.before_iteration(k, history)

    def describe(self) -> list[str]:
        """The chain as text: one line per block (its kind, what it reads and makes), then the
        objective, the constraints and the values reported each iteration."""
        lines = [f"  {type(b).__name__:20s} {', '.join(b.inputs)} -> {b.output}"
                 for b in self.chain.blocks]
        lines.append(f"objective: {self.objective}; constraints (<= 0): "
                     f"{', '.join(self.constraints)}; reported: {', '.join(self.reports) or '-'}")
        return lines

    # -- evaluation -------------------------------------------------------------------------------
    @property
    def n_design(self) -> int:
        """Design variables per material: of the whole mesh, also on a distributed one."""
        return self.field.n if self.design_numbering is None else self.design_numbering.n

    def _forward(self, x):
        """The chain at the design ``x`` (the serial design vector; on a distributed mesh this
        rank's part of rank 0's)."""
        if self.design_numbering is not None:
            x = self.design_numbering.local(x)
        return self.chain.forward(x=x)

    def _gradient(self, name) -> np.ndarray:
        g = np.asarray(self.chain.gradient(name))
        if self.design_numbering is not None:
            g = self.design_numbering.whole(g, self.n_design_fields)
        return g

    def evaluate(self, x: np.ndarray, gradients: bool = True):
        """Return ``f0, fvals`` and, with ``gradients``, ``df0, dfvals`` (shape (m, n))."""
        vals = self._forward(x)
        f0 = float(vals[self.objective])
        f = np.array([vals[c] for c in self.constraints], dtype=float)
        if not gradients:
            return f0, f
        df0 = self._gradient(self.objective)
        df = np.array([self._gradient(c) for c in self.constraints])
        return f0, f, df0, df

    def evaluate_terms(self, x: np.ndarray, gradients: bool = True):
        """Like :meth:`evaluate`, with the objective as its terms: ``F0`` (K values, whose
        maximum is the objective; K = 1 without :attr:`objective_terms`), ``f`` and, with
        ``gradients``, ``dF0`` (shape (K, n)) and ``df`` (shape (m, n))."""
        names = self.objective_terms or (self.objective,)
        vals = self._forward(x)
        F0 = np.array([vals[t] for t in names], dtype=float)
        f = np.array([vals[c] for c in self.constraints], dtype=float)
        if not gradients:
            return F0, f
        dF0 = np.array([self._gradient(t) for t in names])
        df = np.array([self._gradient(c) for c in self.constraints])
        return F0, f, dF0, df

    @property
    def values(self) -> dict:
        return self.chain.values

    def design_density(self) -> np.ndarray:
        """The element densities that show the design (:func:`shown_density`)."""
        return shown_density(self.values)

    def _volume_block(self):
        return next(b for b in self.chain.blocks if b.output == "volume")

    def volume_fraction(self) -> float:
        vol = self._volume_block()
        return vol.fraction(self.values[vol.inputs[0]])

    def greyness(self) -> float:
        """Sigmund's (2007) measure of non-discreteness of the reported design: 4 ρ̄ (1 - ρ̄)
        averaged by area over the design domain (ρ̄1, the material-or-void density, with two
        materials): 0 for a solid-void design, 1 where every element sits at 0.5."""
        vol = self._volume_block()
        rho = np.clip(np.asarray(self.values.get("rho_bar", self.values.get("rho_bar1"))),
                      0.0, 1.0)
        return total(self.mesh, vol.w @ (4.0 * rho * (1.0 - rho))) / vol.total
