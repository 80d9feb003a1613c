"""Settings nobody gave, derived from the case: the mesh size from the domain (and a given
filter radius), the filter radius from the mesh size, the penalty and projection continuation
when a case sets none (:func:`derive_settings`), and the constant of the objective's scale of
a pressure-driven mechanism (:meth:`pacto_ng.case.Case.derived_objective_ref`).

Each derived value is recorded with how it came about (:attr:`pacto_ng.params.Parameters.derived`;
``--show-parameters`` prints it); a setting given by the case, ``--set``, an option or a run's
params.json is never derived.
"""
from __future__ import annotations

from .geometry import bounding_sides
from .meshing import derived_maxh, element_size
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
#: the penalty and the projection continuation: a case that gives none of a group's
#: settings gets it.  The penalty as the built-in pressure cases' (cases/pa_inverter.py
#: ``PA_DEFAULTS``, pneunet, soft-finger, jaw-gripper): p = 1 -> 3 in steps of 0.04.  β from 1
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


def derive_settings(case, params: Parameters) -> Parameters:
    """``params`` with the numerical settings that nobody gave (:meth:`Parameters.unset`)
    derived from the case, each recorded with how (:attr:`Parameters.derived`):

    - ``maxh`` (Netgen elements, ``nelx`` = 0) from the geometry's size, and from a given
      filter radius (:func:`~pacto_ng.meshing.derived_maxh`);
    - ``filter_radius``: :data:`FILTER_ELEMENTS` element sizes, and where ``maxh`` is derived
      too at least :data:`FILTER_SHARE` of the domain's smallest side;
    - a case that gives none of the penalty (or of the projection) schedule's settings:
      :data:`PENALTY` (:data:`PROJECTION`), and with either :data:`CONTINUATION_OPTIMISER`.

    An analysis case (the C-beam) gets the mesh size only.  A derived value stays until one
    of its inputs changes (:meth:`Parameters.replace`)."""
    needs_geometry = ((params.unset("maxh") and params.nelx == 0)
                      or (params.unset("filter_radius") and not case.analysis_only))
    geometry = case.make_geometry(params) if needs_geometry else None
    if params.unset("maxh") and params.nelx == 0:
        params = _derive_maxh(geometry, params)
    if case.analysis_only:
        return params
    if params.unset("filter_radius"):
        params = _derive_filter(geometry, params)
    return _derive_continuation(params)


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


def _derive_filter(geometry, params: Parameters) -> Parameters:
    h = element_size(geometry, maxh=params.maxh, nelx=params.nelx, nely=params.nely,
                     nelz=params.nelz)
    if h is None:
        return params
    radius, how = FILTER_ELEMENTS * h, f"derived: {FILTER_ELEMENTS:g} element sizes of {h:.3g} m"
    sides = bounding_sides(geometry) if "maxh" in params.derived else None
    if sides and FILTER_SHARE * min(sides) > radius:
        radius = FILTER_SHARE * min(sides)
        how = f"derived: {FILTER_SHARE:.3g} of the smallest side {min(sides):.3g} m"
    return params.derive({"filter_radius": float(f"{radius:.4g}")}, {"filter_radius": how},
                         inputs=("maxh", "nelx", "nely", "nelz"))


def _derive_maxh(geometry, params: Parameters) -> Parameters:
    given_radius = params.filter_radius if "filter_radius" in params.given else 0.0
    found = derived_maxh(geometry, filter_radius=given_radius)
    if found is None:
        return params
    maxh, how = found
    return params.derive({"maxh": maxh}, {"maxh": how},
                         inputs=("filter_radius",) if given_radius else ())
