"""Every parameter of a run under its flat name, put together from the parts of the
configuration, each defined and validated next to the code that reads it:

================  ==========================================  ==================================
part              settings                                    defined in
================  ==========================================  ==================================
``mesh``          maxh, nelx, nely, nelz, order,              :mod:`pacto_ng.geometry`
                  unit_elements, mesh_time_limit
``material``      model, plane, thickness, E0, E1, E2, nu,    :mod:`pacto_ng.physics.energy`
                  wang_beta, wang_eta, wang_gamma
``design``        volfrac, volfrac2, filter, filter_radius,   :mod:`pacto_ng.builders`
                  eta, seed_density, init_design
``schedule``      penal, penal_start, penal_step,             :mod:`pacto_ng.optimize.schedules`
                  penal_every, beta, beta_max, beta_every,
                  beta_settle, load_ramp
``loads``         load, k_out                                 :mod:`pacto_ng.physics.loads`
``darcy``         Kv, Ks, eta_k, beta_k, eta_h, beta_h, r,    :mod:`pacto_ng.physics.darcy`
                  delta_s, p_out, load_type, follower_wang,
                  load_sensitivity, inlet
``responses``     objective, se_max, leak_max                 :mod:`pacto_ng.builders`
``newton``        newton_rtol, newton_max_iter,               :mod:`pacto_ng.physics.newton`
                  newton_increment, newton_min_increment,
                  realcompile, solver
``optimization``  iterations, optimizer, move, tol,           :mod:`pacto_ng.optimize.driver`
                  obj_tol, load_adapt
``robustness``    robust, robust_deta, robust_every           :mod:`pacto_ng.robust`
``case``          the case's own options (e.g. the            the case's file
                  cantilever's load_width)
================  ==========================================  ==================================

A case supplies its defaults; ``--set NAME=VALUE`` overrides any of them by its flat name.
``params.E1`` reads a setting by that name, ``params.darcy`` a whole part.

Parameters remember which names were *given* (by the case's defaults, ``--set``, the command's
options, ``pacto_ng.run(**settings)`` or a run's params.json): a setting nobody gave may be
*derived* from the case instead of taking its declared default — the mesh size from the domain,
the filter radius from the mesh size, the continuation when the case sets none.  The rules
are :func:`pacto_ng.derive.derive_settings` (the mesh size's in
:func:`pacto_ng.meshing.derived_maxh`), applied by :meth:`pacto_ng.case.Case.resolve` through
:meth:`Parameters.derive`; ``--show-parameters`` says how each derived value came about
(:attr:`Parameters.derived`).
"""
from __future__ import annotations

import math
from dataclasses import fields

from .builders import DesignSettings, ObjectiveSettings
from .errors import InputError
from .meshing import MeshSettings
from .optimize.driver import OptimizerSettings
from .optimize.schedules import ScheduleSettings
from .physics.darcy import DarcySettings
from .physics.energy import MaterialSettings
from .physics.loads import LoadSettings
from .physics.mixed import FormulationSettings
from .physics.newton import NewtonParameters
from .robust import RobustSettings

#: ``(part name, Settings class)`` of every part of the configuration but the case's
PARTS = (("mesh", MeshSettings), ("mechanics", MaterialSettings),
         ("design", DesignSettings), ("schedule", ScheduleSettings),
         ("loads", LoadSettings), ("darcy", DarcySettings),
         ("responses", ObjectiveSettings), ("newton", NewtonParameters),
         ("elements", FormulationSettings),
         ("optimization", OptimizerSettings), ("robustness", RobustSettings))


def _convert(name: str, text: str, default):
    """``text`` (a command-line value) as the type of ``default``."""
    try:
        if isinstance(default, bool):
            low = text.strip().lower()
            if low in ("1", "true", "yes", "on"):
                return True
            if low in ("0", "false", "no", "off"):
                return False
            raise ValueError(text)
        if isinstance(default, int):
            value = float(text)
            if not math.isfinite(value) or value != int(value):
                raise ValueError(text)
            return int(value)
        if isinstance(default, float):
            return float(text)
        return str(text)
    except (ValueError, OverflowError):
        kind = {bool: "true/false", int: "an integer", float: "a number"}.get(type(default), "text")
        raise InputError(f"--set {name}: cannot read '{text}' as {kind}") from None


class Parameters:
    """Every parameter of a run, by flat name, from the parts of the configuration.

    ``Parameters(E1=1e8, maxh=0.002, ...)`` builds every part with those values (the rest at
    their defaults), each part checking its own values; ``options`` is the case's own part
    (a :class:`~pacto_ng.settings.Settings` instance), if it has one.  Immutable: use
    :meth:`replace` or :meth:`with_overrides` for a changed copy.  An ``E1`` given beside a
    material preset that sets another is an error naming both
    (:meth:`~pacto_ng.physics.energy.MaterialSettings.check_explicit_E1`); the copies this
    class makes pass ``_explicit``, the names given anew (all of ``values`` by default).
    """

    __slots__ = ("_parts", "_index", "_given", "_derived")

    def __init__(self, options=None, _explicit=None, **values):
        index = {}
        for part, cls in PARTS:
            for f in fields(cls):
                index[f.name] = part
        if options is not None:
            for f in fields(options):
                if f.name in index:
                    raise InputError(f"case options: '{f.name}' is already a parameter of the "
                                     f"toolkit ({index[f.name]})")
                index[f.name] = "case"
        unknown = sorted(set(values) - set(index))
        if unknown:
            raise InputError(f"{unknown[0]}: unknown parameter (see --show-parameters)")
        built = {}
        for part, cls in PARTS:
            built[part] = cls(**{k: v for k, v in values.items() if index[k] == part})
        if options is not None:
            import dataclasses

            built["case"] = dataclasses.replace(
                options, **{k: v for k, v in values.items() if index[k] == "case"})
        object.__setattr__(self, "_parts", built)
        object.__setattr__(self, "_index", index)
        object.__setattr__(self, "_given", frozenset(values))
        explicit = values.keys() if _explicit is None else _explicit
        if "E1" in explicit:
            built["mechanics"].check_explicit_E1(values["E1"])
        # name -> (how it was derived, the names it was derived from)
        object.__setattr__(self, "_derived", {})

    def _marked(self, given, derived) -> "Parameters":
        """This object with ``given`` and ``derived`` (see :meth:`derive`) recorded."""
        object.__setattr__(self, "_given", frozenset(given))
        object.__setattr__(self, "_derived", dict(derived))
        return self

    # -- reading -----------------------------------------------------------------------------
    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        parts_ = object.__getattribute__(self, "_parts")
        if name in parts_:
            return parts_[name]
        index = object.__getattribute__(self, "_index")
        if name in index:
            return getattr(parts_[index[name]], name)
        raise AttributeError(f"no parameter '{name}'")

    def __setattr__(self, name, value):
        raise AttributeError("Parameters are immutable: use replace() or with_overrides()")

    @property
    def options(self):
        """The case's own part (None if the case has no options)."""
        return self._parts.get("case")

    @property
    def given(self) -> frozenset:
        """The names given explicitly: by the case's defaults, ``--set``, the command's options,
        ``pacto_ng.run(**settings)`` or a run's params.json (the rest hold their declared
        default, or a derived value)."""
        return self._given

    @property
    def derived(self) -> dict[str, str]:
        """The derived values' names, each with how it was derived (:meth:`derive`)."""
        return {name: why for name, (why, _) in self._derived.items()}

    def unset(self, *names: str) -> list[str]:
        """Those of ``names`` neither given nor derived yet: the ones a derivation may set."""
        return [n for n in names if n not in self._given and n not in self._derived]

    def derive(self, values: dict, why: dict[str, str], inputs=()) -> "Parameters":
        """A copy with ``values`` (flat names) set as derived values: ``why[name]`` says how
        (``--show-parameters`` prints it), ``inputs`` names the settings they were derived
        from.  A later :meth:`replace` of one of ``inputs`` returns them to their declared
        defaults, to be derived again.  Only names that are :meth:`unset` may be derived."""
        closed = [n for n in values if not self.unset(n)]
        if closed:
            raise ValueError(f"derive: '{closed[0]}' is given or derived already")
        new = Parameters(self.options, (), **{**self.to_dict(), **values})
        derived = dict(self._derived)
        for name in values:
            derived[name] = (why[name], frozenset(inputs))
        return new._marked(self._given, derived)

    def keys(self) -> list[str]:
        """Every flat name, the case's options included."""
        return list(self._index)

    @classmethod
    def names(cls) -> list[str]:
        """The flat names of the toolkit's parameters (without any case's options)."""
        return [f.name for _, part in PARTS for f in fields(part)]

    def to_dict(self) -> dict:
        """Every parameter by flat name (params.json, summary.json)."""
        return {name: getattr(self._parts[part], name) for name, part in self._index.items()}

    def describe(self, units: dict[str, str] | None = None) -> list[tuple[str, object, str, str]]:
        """``(name, value, unit, meaning)`` of every parameter, part by part."""
        units = units or {}
        rows = []
        for part in self._parts.values():
            for f in fields(part):
                rows.append((f.name, getattr(part, f.name),
                             units.get(f.name, f.metadata.get("unit", "")),
                             f.metadata.get("help", "")))
        return rows

    # -- changed copies ------------------------------------------------------------------------
    def replace(self, **changes) -> "Parameters":
        """A copy with ``changes`` (flat names) applied and checked; the changed names count as
        given.  A derived value whose inputs change returns to its declared default (to be
        derived again by :meth:`~pacto_ng.case.Case.resolve`)."""
        values = {**self.to_dict(), **changes}
        derived = {}
        for name, (why, inputs) in self._derived.items():
            if name in changes:
                continue
            if inputs & changes.keys():
                values[name] = self._declared_default(name)
                continue
            derived[name] = (why, inputs)
        new = Parameters(self.options, changes.keys(), **values)
        return new._marked(self._given | changes.keys(), derived)

    def _declared_default(self, name: str):
        part = self._parts[self._index[name]]
        return next(f.default for f in fields(part) if f.name == name)

    def with_overrides(self, overrides: dict[str, str]) -> "Parameters":
        """Apply ``NAME=VALUE`` strings, converting to each parameter's declared type."""
        changes = {}
        for name, text in overrides.items():
            if name not in self._index:
                raise InputError(f"--set: unknown parameter '{name}' (see --show-parameters)")
            changes[name] = _convert(name, text, getattr(self, name))
        return self.replace(**changes)

    def with_options(self, options) -> "Parameters":
        """These parameters with the case's own part ``options`` (its defaults) added."""
        return Parameters(options, (), **self.to_dict())._marked(self._given, self._derived)

    def __eq__(self, other):
        return isinstance(other, Parameters) and self.to_dict() == other.to_dict() \
            and type(self.options) is type(other.options)

    def __hash__(self):
        return hash(tuple(sorted((k, repr(v)) for k, v in self.to_dict().items())))

    def __repr__(self):
        changed = {k: v for k, v in self.to_dict().items()}
        return "Parameters(" + ", ".join(f"{k}={v!r}" for k, v in changed.items()) + ")"

    def __reduce__(self):
        return (_rebuild, (self.options, self.to_dict(), self._given, self._derived))


def _rebuild(options, values, given=None, derived=None):
    params = Parameters(options, (), **values)
    if given is None:  # pickled by a version that did not record them
        return params
    return params._marked(given, derived or {})
