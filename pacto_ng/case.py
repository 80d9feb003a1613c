"""Cases as typed data, and the problem (block chain) built from a case and its parameters.

A :class:`Case` is frozen data: a name, a one-line summary, its source, default
:class:`~pacto_ng.params.Parameters`, a geometry (``geometry(params)``: a netgen.occ shape, a
:class:`~pacto_ng.mesh.Layout`, a CAD or mesh file; see :mod:`pacto_ng.geometry`) and a set-up
(``setup(params) -> Setup``: supports, loads, springs, ports, passive regions, objective).  The
built-in cases in ``cases/`` define one each; a user's own case is a Python file that defines
``CASE`` (:func:`load_case_file`).  :func:`build_problem` turns a case and parameters into a
:class:`Problem` through the case's chain (``Case.chain``, :mod:`pacto_ng.builders`): the mesh,
the design field, the chain of blocks and the names of the objective and the constraints.
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import importlib.util
import json
import os
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .builders import OBJECTIVES, Builder, standard_chain
from .core import Chain
from .derive import MECHANISM_RATIO, derive_settings
from .geometry import bounding_sides
from .params import InputError, Parameters
from .physics.loads import Outputs, PointLoad, Port, Spring
from .physics.mechanics import Supports

CASE_MODULES = {
    "mbb": "pacto_ng.cases.mbb",
    "cantilever": "pacto_ng.cases.cantilever",
    "inverter": "pacto_ng.cases.inverter",
    "c-beam": "pacto_ng.cases.c_beam",
    "pa-inverter": "pacto_ng.cases.pa_inverter",
    "pa-gripper": "pacto_ng.cases.pa_gripper",
    "pneunet": "pacto_ng.cases.pneunet",
    "mm-gripper": "pacto_ng.cases.mm_gripper",
    "soft-finger": "pacto_ng.cases.soft_finger",
    "jaw-gripper": "pacto_ng.cases.jaw_gripper",
    "sorotop": "pacto_ng.cases.sorotop",
    "topress": "pacto_ng.cases.topress",
    "cantilever-3d": "pacto_ng.cases.cantilever_3d",
    "pneunet-3d": "pacto_ng.cases.pneunet_3d",
    "pa-inverter-3d": "pacto_ng.cases.pa_inverter_3d",
    "pa-gripper-3d": "pacto_ng.cases.pa_gripper_3d",
    "topress-3d": "pacto_ng.cases.topress_3d",
    "gripper-silicone": "pacto_ng.cases.gripper_silicone",
    "pneunet-silicone": "pacto_ng.cases.pneunet_silicone",
}


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


@dataclass(frozen=True)
class Case:
    """A case: what is optimised, on which geometry, with which defaults.

    Parameters
    ----------
    name : str
        The case's name (``pacto cases``; the default output folder ``output/NAME-MODEL``).
    summary : str
        One line: what it optimises and what it shows.
    source : str
        Where the set-up comes from (a paper, a thesis section, "my lab's gripper").
    defaults : Parameters
        The case's default parameters (``pacto run CASE --show-parameters`` lists them).
    geometry : callable
        ``geometry(params)`` -> a netgen.occ shape with named faces, edges and vertices, a
        :class:`~pacto_ng.mesh.Layout`, a CAD or mesh file path, or an ``ngsolve.Mesh``
        (:mod:`pacto_ng.geometry`).
    setup : callable
        ``setup(params)`` -> :class:`Setup`: supports, loads, springs, ports, passive regions,
        pressure and objective, by the geometry's names.
    load_unit : str
        The unit of ``--load`` ("N", or "Pa" for pressure cases).
    analysis_only : bool
        An analysis, not an optimisation (the C-beam).
    notes : str
        Free text.
    model_orders : dict
        Displacement order per model where it is not 1 (``order`` = 0 resolves through it).
    file : str
        Set by :func:`load_case_file`: the case file it came from.
    options : Settings, optional
        The case's own settings with their defaults (a :class:`~pacto_ng.settings.Settings`
        instance), set like any parameter (``--set NAME=VALUE``) and read as ``params.NAME``.
    chain : callable
        ``chain(b)`` -> :class:`Problem`: the blocks of the case in order, built with the
        :class:`~pacto_ng.builders.Builder` ``b`` (design, energy, pressure, mechanics,
        responses, volume); :func:`~pacto_ng.builders.standard_chain` unless the case needs
        another objective or other reported values (``pacto run CASE --show-chain``).
    """

    name: str
    summary: str
    source: str
    defaults: Parameters
    geometry: Callable  # params -> netgen.occ shape | Layout | file path | ngsolve.Mesh
    setup: Callable  # params -> Setup
    load_unit: str = "N"
    analysis_only: bool = False
    notes: str = ""
    #: displacement order per model where it is not 1 (``order`` = 0, the default, resolves
    #: through this): the knee of the case's trade curve (docs/benchmarks.md)
    model_orders: dict = field(default_factory=dict)
    #: the case file a user's case was loaded from (empty for the built-in cases)
    file: str = ""
    #: the case's own settings (a pacto_ng.Settings instance with their defaults), set like
    #: any parameter: ``--set NAME=VALUE``, ``params.NAME``
    options: object = None
    #: the case's chain of blocks (``chain(builder) -> Problem``)
    chain: Callable = standard_chain

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError("case: name must be a non-empty string")
        if not isinstance(self.defaults, Parameters):
            raise InputError(f"case '{self.name}': defaults must be Parameters (got "
                             f"{type(self.defaults).__name__})")
        for attr in ("geometry", "setup", "chain"):
            if not callable(getattr(self, attr)):
                raise InputError(f"case '{self.name}': {attr} must be a function of the "
                                 "parameters")
        if self.options is not None and self.defaults.options is None:
            object.__setattr__(self, "defaults", self.defaults.with_options(self.options))

    def parameters(self, values: dict) -> Parameters:
        """The case's parameters with ``values`` (flat names, e.g. a run's params.json)."""
        known = set(self.defaults.keys())
        # run folders of the version before case options kept every case's options
        legacy = {k for k in ("load_width", "output_width", "k_in")
                  if k in values and k not in known and values[k] == 0.0}
        return self.defaults.replace(**{k: v for k, v in values.items() if k not in legacy})

    def make_geometry(self, params: Parameters):
        """The case's geometry for ``params`` (an error in a user's case file: one line)."""
        return self._user_call(self.geometry, params)

    def make_setup(self, params: Parameters) -> "Setup":
        """The case's set-up for ``params`` (an error in a user's case file: one line), with
        ``objective_ref`` derived where it gives none (:meth:`derived_objective_ref`)."""
        setup = self._user_call(self.setup, params)
        if not isinstance(setup, Setup):
            raise InputError(f"case '{self.name}': setup(params) returned a "
                             f"{type(setup).__name__}, not a Setup")
        found = self.derived_objective_ref(params, setup)
        if found is not None:
            setup = dataclasses.replace(setup, objective_ref=found[0])
        return setup

    def derived_objective_ref(self, params: Parameters, setup: "Setup | None" = None):
        """``(objective_ref, how)`` for a pressure-driven mechanism (objective ``mechanism``)
        whose set-up (``setup``, or the case's own for ``params``) gives no
        ``objective_ref``, else None: ``MECHANISM_RATIO / (P_in L t)``
        in 2D, ``MECHANISM_RATIO / (P_in L w)`` in 3D, ``L`` and ``w`` the largest and the
        smallest side of the domain's bounding box, the form of the built-in pressure cases
        (the driver's own scale, 10/|f0(x0)|, fails here: the initial design barely moves the
        output, and MMA then drops the volume constraint)."""
        if setup is None:
            setup = self._user_call(self.setup, params)
        if not isinstance(setup, Setup) or setup.objective_ref > 0 or setup.pressure is None:
            return None
        if (params.objective or setup.objective) != "mechanism":
            return None
        sides = bounding_sides(self.make_geometry(params))
        if sides is None or not min(sides) > 0 or params.load == 0:
            return None
        width = params.thickness if len(sides) == 2 else min(sides)
        ref = MECHANISM_RATIO / (abs(params.load) * max(sides) * width)
        what = "t" if len(sides) == 2 else "w"
        return ref, (f"derived: {MECHANISM_RATIO:g} / (P_in L {what}), L = {max(sides):.3g} m, "
                     f"{what} = {width:.3g} m (the built-in pressure cases' form)")

    def make_problem(self, builder: Builder) -> "Problem":
        """The case's chain on ``builder`` (an error in a user's case file: one line)."""
        problem = self._user_call(self.chain, builder)
        if not isinstance(problem, Problem):
            raise InputError(f"case '{self.name}': chain(b) returned a "
                             f"{type(problem).__name__}, not a Problem (end it with "
                             "b.problem(...))")
        return problem

    def _user_call(self, fn, arg):
        if not self.file:
            return fn(arg)
        try:
            return fn(arg)
        except InputError:
            raise
        except Exception as err:  # noqa: BLE001 - any error of a user's code, shown as file:line
            raise user_code_error(err, self.file) from None

    def order_for(self, model: str) -> int:
        """The case's displacement order for ``model``: its defaults' order if they fix one,
        else ``model_orders`` (1 for a model it does not name)."""
        return int(self.defaults.order or self.model_orders.get(model, 1))

    def resolve(self, params: Parameters) -> Parameters:
        """``params`` with the settings nobody gave derived from the case
        (:func:`derive_settings`), and ``order`` = 0 replaced by the case's order for its
        model."""
        params = derive_settings(self, params)
        if params.order or params.model == "auto":
            return params
        return params.replace(order=self.order_for(params.model))


def is_case_file(name: str) -> bool:
    """Whether ``name`` names a case file (a path ending in ``.py``) rather than a built-in."""
    return str(name).endswith(".py")


def get_case(name: str) -> Case:
    """A built-in case by name, or a user's case from a file ``path/to/case.py``."""
    if is_case_file(name):
        return load_case_file(name)
    mod = CASE_MODULES.get(name)
    if mod is None:
        raise InputError(f"unknown case '{name}' (built-in: {', '.join(CASE_MODULES)}; or give "
                         "the path of a case file, e.g. my_case.py)")
    try:
        return importlib.import_module(mod).CASE
    except ModuleNotFoundError as err:
        raise InputError(f"case '{name}' is not available in this installation ({err})") from None


def user_code_error(err: BaseException, file: str) -> InputError:
    """A one-line error for an exception raised by a user's case file: ``FILE:LINE: Kind:
    message`` at the deepest line of that file in the traceback."""
    path = os.path.realpath(file)
    if isinstance(err, SyntaxError) and err.filename and os.path.realpath(err.filename) == path:
        return InputError(f"{file}:{err.lineno}: SyntaxError: {err.msg}")
    line = None
    for frame in traceback.extract_tb(err.__traceback__):
        if os.path.realpath(frame.filename) == path:
            line = frame.lineno
    where = f"{file}:{line}" if line is not None else file
    msg = str(err).splitlines()[0] if str(err) else ""
    return InputError(f"{where}: {type(err).__name__}: {msg}".rstrip(": "))


def load_case_file(path: str | os.PathLike) -> Case:
    """The ``CASE`` of a user's case file (a Python file built with the public API).

    The file is imported as a module of its own (its folder first on ``sys.path``, so that it
    may import files beside it); the returned case records the file's absolute path, which a
    run folder keeps so that ``pacto resume``, ``analyse``, ``export`` ... find it again."""
    fp = Path(path)
    if not fp.is_file():
        raise InputError(f"case file '{path}' does not exist")
    full = str(fp.resolve())
    key = "pacto_case_" + hashlib.sha1(full.encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(key, full)
    module = importlib.util.module_from_spec(spec)
    folder = str(fp.resolve().parent)
    sys.path.insert(0, folder)
    sys.modules[key] = module
    try:
        spec.loader.exec_module(module)
    except InputError as err:
        sys.modules.pop(key, None)
        raise InputError(f"{path}: {err}") from None
    except SystemExit:
        sys.modules.pop(key, None)
        raise InputError(f"{path}: the case file called sys.exit() when imported (guard its "
                         "script part with if __name__ == '__main__':)") from None
    except Exception as err:  # noqa: BLE001 - any error of a user's code, shown as file:line
        sys.modules.pop(key, None)
        raise user_code_error(err, str(path)) from None
    finally:
        if sys.path and sys.path[0] == folder:
            sys.path.pop(0)
    case = getattr(module, "CASE", None)
    if case is None:
        raise InputError(f"{path}: defines no CASE (a pacto_ng.Case; see 'pacto new')")
    if not isinstance(case, Case):
        raise InputError(f"{path}: CASE is a {type(case).__name__}, not a pacto_ng.Case")
    return dataclasses.replace(case, file=full)


def case_of_run(info: dict, command: str) -> Case:
    """The case a run folder's params.json names: its case file if it has one, else the
    built-in case of that name."""
    file = info.get("case_file") or ""
    if file:
        if not Path(file).is_file():
            raise InputError(f"{command}: the run's case file '{file}' no longer exists")
        return load_case_file(file)
    name = info["case"]
    if name not in CASE_MODULES:
        raise InputError(f"{command}: the run's case '{name}' was built in a script, not in a "
                         "case file; from that script use pacto_ng.load_result(folder, "
                         "case=CASE), or move CASE into a case file")
    return get_case(name)


def read_run_params(folder, command: str, case: Case | None = None) -> tuple[dict, Case, Parameters]:
    """A run folder's params.json: its content, its case (``case`` if given: it must be the
    run's) and its parameters; one-line InputError naming the file for anything damaged."""
    fp = Path(folder) / "params.json"
    try:
        info = json.loads(fp.read_text())
    except FileNotFoundError:
        raise InputError(f"{command}: '{folder}' holds no run (no params.json)") from None
    except (OSError, ValueError) as err:
        raise InputError(f"{command}: '{fp}' is unreadable ({type(err).__name__})") from None
    if not (isinstance(info, dict) and isinstance(info.get("case"), str)
            and isinstance(info.get("params"), dict)
            and isinstance(info.get("case_file") or "", str)):
        raise InputError(f"{command}: '{fp}' is not a run's parameter file (it needs a case "
                         "name and a table of parameters)")
    if case is None:  # an error in a user's case file is shown as itself
        case = case_of_run(info, command)
    elif case.name != info["case"]:
        raise InputError(f"{command}: '{folder}' is a run of '{info['case']}', not of "
                         f"'{case.name}'")
    try:
        params = case.parameters(info["params"])
    except InputError as err:
        raise InputError(f"{command}: '{fp}': {err}") from None
    return info, case, params


def available_cases() -> list[Case]:
    """The built-in cases whose modules are installed."""
    out = []
    for name, mod in CASE_MODULES.items():
        if importlib.util.find_spec(mod) is not None:
            out.append(get_case(name))
    return out


# ------------------------------------------------------------------------------------------
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
        """The element densities that show the design: ρ̄, or with two materials ρ̄1 (1 + ρ̄2)
        / 2 (void 0, the soft material 1/2, the stiff material 1)."""
        vals = self.values
        if "rho_bar" in vals:
            return np.asarray(vals["rho_bar"])
        return np.asarray(vals["rho_bar1"]) * (1 + np.asarray(vals["rho_bar2"])) / 2.0

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
        from .parallel import total

        return total(self.mesh, vol.w @ (4.0 * rho * (1.0 - rho))) / vol.total


def domain_size(params: Parameters, width: float, height: float) -> tuple[float, float]:
    """``(width, height)``, or ``(nelx, nely)`` with ``unit_elements`` (1 x 1 elements, the
    set-up of the classic MATLAB codes)."""
    if params.unit_elements:
        return float(params.nelx), float(params.nely)
    return width, height


def mesh_for(case: Case, params: Parameters):
    """The case's meshed domain (:class:`~pacto_ng.geometry.Meshed`): Netgen triangles or
    tetrahedra of size maxh, or structured quads (hexahedra) if nelx > 0 (a Layout; a Box with
    nelz)."""
    from .geometry import mesh_geometry

    # the resources check (pacto_ng.resources) before meshing: a follower load makes the
    # tangent unsymmetric (umfpack), otherwise it is symmetric (sparsecholesky)
    return mesh_geometry(case.make_geometry(params), maxh=params.maxh, nelx=params.nelx,
                         nely=params.nely, nelz=params.nelz, order=params.order,
                         mesh_time_limit=params.mesh_time_limit,
                         solver="umfpack" if params.load_type == "follower" else "sparsecholesky",
                         linear_solver=params.solver)


def build_problem(case: Case, params: Parameters, comm=None, meshed=None) -> Problem:
    """The case's problem: its set-up and mesh, checked against each other, then its chain
    (``case.chain``, :mod:`pacto_ng.builders`).  With an mpi4py communicator ``comm`` of
    several ranks, rank 0 meshes and checks, then the mesh is distributed
    (:func:`pacto_ng.parallel.distribute`) and every rank builds the chain on its part; every
    rank must call this.  ``meshed`` (serial only): the case's domain meshed already
    (:class:`~pacto_ng.geometry.Meshed`, e.g. a run's, to analyse its design at another
    order on the same elements)."""
    from .geometry import check_inlet_touches_design, check_setup_names, check_vectors

    if case.analysis_only:
        raise InputError(f"case '{case.name}' is an analysis, not an optimisation")
    params = case.resolve(params)
    if params.model == "auto":
        raise InputError("model: 'auto' is chosen by 'pacto run' (pacto_ng.auto.choose), "
                         "not by build_problem")
    setup = case.make_setup(params)
    if params.volfrac2 > 0 and setup.materials == 1:
        raise InputError(f"volfrac2: case '{case.name}' has one material (volfrac2 limits the "
                         "stiff material of a two-material case)")
    parallel = comm is not None and comm.size > 1
    meshed, failure = None, None
    if not parallel or comm.rank == 0:
        try:
            meshed = meshed or mesh_for(case, params)
            check_setup_names(meshed.mesh, setup)
            check_vectors(meshed.mesh, setup)
            if setup.pressure is not None:
                check_inlet_touches_design(meshed.mesh, setup.pressure.inlet, setup.void)
        except InputError as err:
            if not parallel:
                raise
            failure = str(err)
    numbering = None
    if parallel:
        failure = comm.bcast(failure, root=0)
        if failure is not None:
            raise InputError(failure)
        from .parallel import distribute

        meshed, numbering = distribute(meshed, comm)

    builder = Builder(case, params, meshed, setup)
    if params.robust:
        if case.chain is not standard_chain:
            raise InputError(f"robust: case '{case.name}' builds its own chain; the robust "
                             "formulation replaces the standard chain only")
        from .robust import robust_chain

        problem = robust_chain(builder)
    else:
        problem = case.make_problem(builder)
    if numbering is not None:
        from .parallel import DesignNumbering

        problem.numbering = numbering
        problem.design_numbering = DesignNumbering(numbering, problem.field)
    return problem
