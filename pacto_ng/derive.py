"""Settings nobody gave, derived from the case: the mesh size from the domain (and a given
filter radius), the filter radius from the mesh size, the penalty and projection continuation
when a case sets none (:func:`derive_settings`), and the constant of the objective's scale of
a pressure-driven mechanism (:meth:`pacto_ng.case.Case.derived_objective_ref`); and the
library's defaults for pressure-actuated mechanisms that the built-in cases start from
(:data:`PRESSURE_DEFAULTS`, :func:`se_default`, :func:`objective_ref`).

Each derived value is recorded with how it came about (:attr:`pacto_ng.params.Parameters.derived`;
``--show-parameters`` prints it); a setting given by the case, ``--set``, an option or a run's
params.json is never derived.
"""
from __future__ import annotations

from .geometry_kinds import kind_of
from .meshing import derived_maxh
from .params import Parameters


#: the typical |-Δ/SE| of a finished pressure-driven mechanism in units of 1/(P_in L t) (the
#: built-in cases use 0.1-3: soft-finger 0.5, pneunet 0.24, pa-inverter 3), for a set-up that
#: gives no objective_ref (:meth:`pacto_ng.case.Case.derived_objective_ref`)
MECHANISM_RATIO = 0.5
#: the filter radius of a case that gives none, in element sizes (the rule of
#: ``filter_radius`` = 0, :mod:`pacto_ng.builders`, now recorded as a length) ...
FILTER_ELEMENTS = 3.0
#: ... and, where the mesh size is derived too, at least this share of the domain's smallest
#: side: the smallest member the design may have (the built-in pressure cases: 1/5.5-1/8,
#: e.g. pa-inverter 0.012 m of 0.1 m, pneunet-silicone 0.002 m of 0.015 m)
FILTER_SHARE = 1.0 / 8.0
#: the Darcy drainage depth Δs (``delta_s``) of a pressure case that gives none, in element
#: sizes: the pressure falls to r P_in within this depth of solid, so a wall of the filter's
#: smallest member (2 R = 6 elements) holds it back by r^6; one element is the thinnest
#: layer the mesh resolves (the built-in pressure cases: 0.5-1.5 element sizes)
DRAIN_ELEMENTS = 1.0
#: default strain-energy limit of objective output_se in units of P_in² V / E1 (V: the domain's
#: volume, t W H in 2D) -- the energy scale of a pressure P_in on a body of modulus E1; the
#: default mechanism designs store 14-18 of these units (measured), so 15 gives designs of
#: similar SE
SE_FACTOR = 15.0

#: the parameters the pressure-actuated mechanisms start from (pa-inverter, pa-gripper,
#: mm-gripper, pa-inverter-3d): thesis Table 6.1 (Δs = 0.002 m among them), and a continuation that gives clean designs
#: at the thesis mesh (measured, docs/studies.md): p = 1 -> 3 in steps of 0.04, then
#: β = 1 -> 32 doubling every 15 iterations, move limit 0.05 (0.1 oscillates from the start);
#: the filter radius is a length (3 thesis mesh sizes), so that finer meshes resolve the same
#: design.  The run stops once -Δ/SE changes by less than 0.1 % in each of 5 iterations
#: (obj_tol): on the final problem GCMMA lowers it by 0.02-0.1 % per iteration for tens of
#: iterations while the design barely changes (docs/studies.md, "Convergence at defaults")
PRESSURE_DEFAULTS = Parameters(
    model="linear", maxh=0.004, plane="strain", thickness=1e-3, E1=3e9, E0=3e3, nu=0.4,
    volfrac=0.2, filter="helmholtz", filter_radius=0.012, delta_s=0.002, penal=3.0,
    penal_start=1.0, penal_step=0.04, beta=1.0, beta_max=32.0, beta_every=15, load=1e6,
    k_out=1e4, iterations=160, move=0.05, tol=0.01, obj_tol=1e-3)

#: ... and in 3D (pa-inverter-3d, pa-gripper-3d): the 2D settings that carry over (the mesh,
#: the plane and the thickness do not), the output spring of the quarter model, the penalty
#: from 2
PRESSURE_DEFAULTS_3D = PRESSURE_DEFAULTS.replace(maxh=0.005, plane="strain", thickness=1e-3,
                                                 k_out=2e5, penal_start=2.0)

#: the penalty and the projection continuation: a case that gives none of a group's
#: settings gets it.  The penalty as the built-in pressure cases' (:data:`PRESSURE_DEFAULTS`, pneunet, soft-finger, jaw-gripper): p = 1 -> 3 in steps of 0.04.  β from 1
#: doubling every 15 iterations, or as soon as the objective settles (``beta_settle``, as the
#: 3D built-in cases), to 64: on tests/cases/user_finger.py the built-in 2D cases' end, 32
#: every 15, left greyness 0.026 after 132 iterations, this one 0.011 after 100 (measured
#: 2026-12, volume fraction 0.35 and 0.3)
PENALTY = ({"penal_start": 1.0, "penal_step": 0.04},
           ("penal", "penal_start", "penal_step", "penal_every"))
PROJECTION = ({"beta_max": 64.0, "beta_every": 15, "beta_settle": 3e-3},
              ("beta", "beta_max", "beta_every", "beta_settle"))
#: ... and with either, their move limit (0.1 oscillates), objective tolerance and iteration
#: cap, each where the case gives none
CONTINUATION_OPTIMISER = {"move": 0.05, "obj_tol": 1e-3, "iterations": 160}


def domain_size(params: Parameters, width: float, height: float) -> tuple[float, float]:
    """``(width, height)``, or ``(nelx, nely)`` with ``unit_elements`` (1 x 1 elements, the
    set-up of the classic MATLAB codes)."""
    if params.unit_elements:
        return float(params.nelx), float(params.nely)
    return width, height


def se_default(p: Parameters, volume: float) -> float:
    """Default limit of objective ``output_se``: ``SE_FACTOR · P_in² V / E1`` for a domain of
    volume ``V`` (``t W H`` in 2D: :func:`domain_size`)."""
    return SE_FACTOR * p.load ** 2 * volume / p.E1


def objective_ref(p: Parameters, length: float, width: float, ratio: float,
                  se_max: float) -> float:
    """Typical magnitude of the objective, which the run scales to 10 (Setup.objective_ref).

    ``-Δ/SE`` is of order ``ratio / (P_in L w)`` (``L`` the domain's length, ``w`` the
    thickness in 2D or the depth in 3D; dimensionless ``ratio``: the default designs reach
    8-11 for the inverter and grippers, 0.24 for the PneuNet); for ``output_se`` the
    objective ``-Δ`` is of order that times the SE limit ``se_max`` (``p.se_max`` wins where
    set).  0 for other objectives.
    """
    mech = ratio / (p.load * length * width)
    objective = p.objective or "mechanism"
    if objective == "mechanism":
        return mech
    if objective == "output_se":
        return mech * (p.se_max or se_max)
    return 0.0


def mechanism_scales(p: Parameters, width: float, height: float,
                     ratio: float) -> tuple[float, float]:
    """``(se_max, objective_ref)`` of a 2D pressure-driven mechanism on a ``width`` x
    ``height`` domain (:func:`domain_size`) of thickness ``p.thickness``: :func:`se_default`
    and :func:`objective_ref` with ``L = W``, ``w = t``."""
    W, H = domain_size(p, width, height)
    se_max = se_default(p, p.thickness * W * H)
    return se_max, objective_ref(p, W, p.thickness, ratio, se_max)


def derive_settings(case, params: Parameters) -> Parameters:
    """``params`` with the numerical settings that nobody gave (:meth:`Parameters.unset`)
    derived from the case, each recorded with how (:attr:`Parameters.derived`):

    - ``maxh`` (Netgen elements, ``nelx`` = 0) from the geometry's size, and from a given
      filter radius (:func:`~pacto_ng.meshing.derived_maxh`);
    - ``filter_radius``: :data:`FILTER_ELEMENTS` element sizes, and where ``maxh`` is derived
      too at least :data:`FILTER_SHARE` of the domain's smallest side;
    - ``delta_s`` of a pressure case: :data:`DRAIN_ELEMENTS` element sizes;
    - a case that gives none of the penalty (or of the projection) schedule's settings:
      :data:`PENALTY` (:data:`PROJECTION`), and with either :data:`CONTINUATION_OPTIMISER`.

    An analysis case (the C-beam) gets the mesh size only.  A derived value stays until one
    of its inputs changes (:meth:`Parameters.replace`)."""
    drains = case.load_unit == "Pa" and not case.analysis_only  # a pressure case
    needs_geometry = ((params.unset("maxh") and params.nelx == 0)
                      or (params.unset("filter_radius") and not case.analysis_only)
                      or (drains and params.unset("delta_s")))
    kind = kind_of(case.make_geometry(params)) if needs_geometry else None
    if params.unset("maxh") and params.nelx == 0:
        params = _derive_maxh(kind, params)
    if case.analysis_only:
        return params
    if params.unset("filter_radius"):
        params = _derive_filter(kind, params)
    if drains and params.unset("delta_s"):
        params = _derive_drainage(kind, params)
    return _derive_continuation(params)


def _element_size(kind, params: Parameters) -> float | None:
    """The element size the mesh options of ``params`` give the geometry's ``kind``."""
    return kind.element_size(params.maxh, (params.nelx, params.nely, params.nelz))


def _derive_drainage(kind, params: Parameters) -> Parameters:
    h = _element_size(kind, params)
    if h is None:
        return params
    return params.derive({"delta_s": float(f"{DRAIN_ELEMENTS * h:.4g}")},
                         {"delta_s": f"derived: {DRAIN_ELEMENTS:g} element size of {h:.3g} m"},
                         inputs=("maxh", "nelx", "nely", "nelz"))


def _derive_continuation(params: Parameters) -> Parameters:
    values, why = {}, {}
    for (group, names), what in (
            (PENALTY, "penalty schedule: p = 1 -> 3 by 0.04, as the built-in pressure cases"),
            (PROJECTION, "projection schedule: β doubled every 15 iterations, or once the "
                         "objective settles, to 64")):
        if len(params.unset(*names)) == len(names):
            values.update(group)
            why.update(dict.fromkeys(group, f"derived: the case sets no {what}"))
    if not values:
        return params
    more = {k: v for k, v in CONTINUATION_OPTIMISER.items() if params.unset(k)}
    why.update(dict.fromkeys(more, "derived: with the derived continuation, as the built-in "
                                   "pressure cases"))
    return params.derive({**values, **more}, why)


def _derive_filter(kind, params: Parameters) -> Parameters:
    h = _element_size(kind, params)
    if h is None:
        return params
    radius, how = FILTER_ELEMENTS * h, f"derived: {FILTER_ELEMENTS:g} element sizes of {h:.3g} m"
    sides = kind.sides if "maxh" in params.derived else None
    if sides and FILTER_SHARE * min(sides) > radius:
        radius = FILTER_SHARE * min(sides)
        how = f"derived: {FILTER_SHARE:.3g} of the smallest side {min(sides):.3g} m"
    return params.derive({"filter_radius": float(f"{radius:.4g}")}, {"filter_radius": how},
                         inputs=("maxh", "nelx", "nely", "nelz"))


def _derive_maxh(kind, params: Parameters) -> Parameters:
    given_radius = params.filter_radius if "filter_radius" in params.given else 0.0
    found = derived_maxh(kind, filter_radius=given_radius)
    if found is None:
        return params
    maxh, how = found
    return params.derive({"maxh": maxh}, {"maxh": how},
                         inputs=("filter_radius",) if given_radius else ())
