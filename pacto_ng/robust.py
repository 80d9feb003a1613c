"""The robust formulation: the design optimised for its worst realisation under a uniform
erosion or dilation of its boundary (``--set robust=1`` or ``2``).

The design field is filtered once; projections of the filtered field ρ̃ at shifted thresholds
give the realisations (Wang, Lazarov & Sigmund 2011, Struct. Multidisc. Optim. 43:767-784):

* ``robust=1``: eroded ρ̄_e = H(ρ̃; η + Δη), intermediate ρ̄ = H(ρ̃; η) and dilated
  ρ̄_d = H(ρ̃; η - Δη).  Each has its own pressure, mechanics and responses.  The objective
  is the worst case ``max(f_e, f_i, f_d)``, solved with MMA's bound formulation (minimise z
  subject to ``f_k - z <= 0``; :class:`~pacto_ng.optimize.mma.Optimizer` with ``terms``).
  The volume constraint is on the dilated design, ``V(ρ̄_d) <= V*_d``, with the target
  updated every ``robust_every`` iterations to ``V*_d = V* V_d / V_i`` (the dilated and
  intermediate volume fractions of the last iteration before the update), so that the
  intermediate design keeps the volume V*; the set-up's own constraints (the strain-energy
  limit of objective ``output_se``) hold for all three.
* ``robust=2`` (SoRoTop, Kumar 2023): eroded and blueprint (η) designs; the worst case of the
  two, the volume constraint on the blueprint, the set-up's constraints (SoRoTop's
  strain-energy limit) on the eroded design.

The intermediate (blueprint) design keeps the standard names (``rho_bar``, ``p``, ``u``,
``delta``, ``se``): it is the design that is saved, thresholded and analysed; the eroded and
dilated values carry ``_e`` and ``_d``.  Each realisation's objective is reported as
``<objective>_e``, ``_i``, ``_d`` (history.csv columns), the worst case is the problem's
objective ``worst_case``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .builders import DesignChain, Responses
from .design import FixPassive
from .errors import InputError
from .filters import HeavisideProjection
from .responses import Volume
from .settings import Settings, setting


@dataclass(frozen=True)
class RobustSettings(Settings):
    """The robust formulation: which one, the threshold shift Δη, the volume-target update."""

    robust: int = setting(0, "", "0: off | 1: worst case of the eroded, intermediate and "
                          "dilated designs (η+Δη, η, η-Δη), volume on the dilated one | 2: "
                          "SoRoTop's: worst case of the eroded and blueprint designs, volume on "
                          "the blueprint, the set-up's SE limit on the eroded one",
                          choices=(0, 1, 2))
    robust_deta: float = setting(0.1, "", "threshold shift Δη of the eroded (η+Δη) and "
                                 "dilated (η-Δη) designs", range="(0, 0.5)")
    robust_every: int = setting(20, "", "iterations between updates of the dilated design's "
                                "volume target V*·V_d/V_i (robust=1)", range="[1, 1000000]")


class WorstCase:
    """Block ``(f_1, ..., f_K) -> max_k f_k``; backward: ``g`` to the largest (the first of
    equal ones), 0 to the others (the derivative where the maximum is unique)."""

    def __init__(self, inputs, output="worst_case"):
        self.inputs, self.output = tuple(inputs), output
        self._k = 0

    def forward(self, *values):
        vals = [float(v) for v in values]
        self._k = int(np.argmax(vals))
        return vals[self._k]

    def backward(self, g):
        return tuple(float(g) if i == self._k else 0.0 for i in range(len(self.inputs)))


class Alias:
    """Block ``a -> a``: a scalar under a second name (a realisation's objective in the
    history)."""

    def __init__(self, inputs, output):
        self.inputs, self.output = tuple(inputs), output

    def forward(self, a):
        return float(a)

    def backward(self, g):
        return (g,)


class VolumeFraction(Volume):
    """Block ``ρ̄ -> Σ a_e ρ̄_e / Σ a_e`` over the design elements (a reported value)."""

    def __init__(self, field, inputs, output):
        super().__init__(field, 0.5, inputs=inputs, output=output)

    def forward(self, rho):
        return self.fraction(rho)

    def backward(self, g):
        return (g * self.w / self.total,)


class VolumeTarget:
    """The dilated design's volume target of ``robust=1``: ``V*_d = V* V_d / V_i`` with the
    fractions of iteration ``j = every * floor(k / every) - 1`` read from the history (V* before
    the first update), so that a resumed run sets the target of the uninterrupted one."""

    def __init__(self, block: Volume, volfrac: float, every: int, names=("vol_d", "vol_i")):
        self.block, self.volfrac, self.every, self.names = block, float(volfrac), int(every), names

    def target(self, k: int, history: list) -> float:
        j = (k // self.every) * self.every - 1
        rows = [r for r in history if r["iteration"] <= j] if j >= 0 else []
        if not rows:
            return self.volfrac
        vd, vi = (float(rows[-1][n]) for n in self.names)
        if not vi > 0:
            return self.volfrac
        return min(self.volfrac * vd / vi, 1.0 - 1e-9)

    def __call__(self, k: int, history: list) -> None:
        self.block.volfrac = self.target(k, history)


def robust_chain(b):
    """The chain of ``--set robust=1`` or ``2`` for a case whose chain is the standard one:
    the realisations of the design, each with its pressure, mechanics and responses, their
    worst case as the objective (module docstring)."""
    params, mode = b.params, b.params.robust
    if b.setup.materials != 1:
        raise InputError(f"robust: case '{b.case.name}' has two design fields; the robust "
                         "formulation is implemented for one")
    eta, deta = params.eta, params.robust_deta
    if not (eta - deta > 0 and eta + deta < 1):
        raise InputError(f"robust_deta: the thresholds η ± Δη must lie in (0, 1) (η {eta:g}, "
                         f"Δη {deta:g})")
    design = b.design()  # the intermediate (blueprint) design: rho_bar
    model = b.energy(design)
    pressure = b.pressure(model, design)
    mech = b.mechanics(model, design, pressure)
    resp = b.responses(mech, pressure)
    obj = resp.objective
    blocks, projections = list(design.blocks), list(design.projections)
    tags = {"e": eta + deta, "d": eta - deta} if mode == 1 else {"e": eta + deta}
    realised = {}  # tag -> (blocks, responses, mechanics)
    for tag, eta_k in tags.items():
        pr = HeavisideProjection(params.beta, eta_k, inputs=("rho_tilde",),
                                 output=f"rho_proj_{tag}")
        fix = FixPassive(design.field, inputs=(pr.output,), output=f"rho_bar_{tag}")
        blocks += [pr, fix]
        projections.append(pr)
        d_k = DesignChain(design.field, [pr, fix], [pr], design.penal, (fix.output,))
        m_k = b.energy(d_k)
        p_k = b.pressure(m_k, d_k, suffix=f"_{tag}")
        mech_k = b.mechanics(m_k, d_k, p_k, suffix=f"_{tag}")
        r_k = b.responses(mech_k, p_k, suffix=f"_{tag}")
        realised[tag] = (p_k.blocks + [mech_k] + r_k.blocks, r_k, mech_k)
    terms = [f"{obj}_e", f"{obj}_i"] + ([f"{obj}_d"] if mode == 1 else [])
    extra = [blk for tag in tags for blk in realised[tag][0]]
    extra += [Alias((obj,), f"{obj}_i"), WorstCase(terms)]
    reports = list(resp.reports) + [r for tag in tags for r in realised[tag][1].reports] + terms
    constraints = list(realised["e"][1].constraints)
    if mode == 1:
        constraints += resp.constraints + realised["d"][1].constraints
    response = Responses(resp.blocks + extra, "worst_case", reports, constraints)
    whole = DesignChain(design.field, blocks, projections, design.penal, design.names)
    volume = b.volume(design)  # V(ρ̄)/V* - 1: the constraint of robust=2, the reported fraction
    hook = None
    if mode == 1:
        vol_d = Volume(design.field, params.volfrac, inputs=("rho_bar_d",), output="volume_d")
        fractions = [VolumeFraction(design.field, (n,), f"vol_{t}")
                     for n, t in (("rho_bar", "i"), ("rho_bar_d", "d"))]
        hook = VolumeTarget(vol_d, params.volfrac, params.robust_every)
        volume = Responses(volume.blocks + [vol_d] + fractions, "volume", ["vol_i", "vol_d"],
                           ["volume_d"])
    response.reports += volume.reports
    volume.reports = []
    problem = b.problem(whole, pressure, mech, response, volume)
    problem.objective_terms = tuple(terms)
    problem.extra_mechanics = [realised[tag][2] for tag in tags]
    problem.before_iteration = hook
    return problem
