"""Cases as typed data, and the problem (block chain) built from a case and its parameters.

A :class:`Case` is frozen data: a name, a one-line summary, its source, default
:class:`~pacto_ng.params.Parameters`, a geometry (``geometry(params)``: a netgen.occ shape, a
:class:`~pacto_ng.mesh.Layout`, a CAD or mesh file; see :mod:`pacto_ng.geometry`) and a set-up
(``setup(params) -> Setup``: supports, loads, springs, ports, passive regions, objective).  The
built-in cases in ``cases/`` define one each; a user's own case is a Python file that defines
``CASE`` (:func:`load_case_file`).  :func:`build_problem` turns a case and parameters into a
:class:`Problem`: the mesh, the design field, the chain of blocks and the names of the
objective and the constraints.
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import importlib.util
import os
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .core import Chain
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
}

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
    # typical magnitude of the objective; the run scales it to 10/objective_ref.  0: the
    # driver's 10/|f0(x0)|, which fails for mechanisms whose initial design barely moves the
    # output (f0(x0) ≈ 0: the scaled objective then grows by 100x and MMA drops the volume
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

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError("case: name must be a non-empty string")
        if not isinstance(self.defaults, Parameters):
            raise InputError(f"case '{self.name}': defaults must be Parameters (got "
                             f"{type(self.defaults).__name__})")
        for attr in ("geometry", "setup"):
            if not callable(getattr(self, attr)):
                raise InputError(f"case '{self.name}': {attr} must be a function of the "
                                 "parameters")

    def make_geometry(self, params: Parameters):
        """The case's geometry for ``params`` (an error in a user's case file: one line)."""
        return self._user_call(self.geometry, params)

    def make_setup(self, params: Parameters) -> "Setup":
        """The case's set-up for ``params`` (an error in a user's case file: one line)."""
        setup = self._user_call(self.setup, params)
        if not isinstance(setup, Setup):
            raise InputError(f"case '{self.name}': setup(params) returned a "
                             f"{type(setup).__name__}, not a Setup")
        return setup

    def _user_call(self, fn, params):
        if not self.file:
            return fn(params)
        try:
            return fn(params)
        except InputError:
            raise
        except Exception as err:  # noqa: BLE001 - any error of a user's code, shown as file:line
            raise user_code_error(err, self.file) from None

    def order_for(self, model: str) -> int:
        """The case's displacement order for ``model``: its defaults' order if they fix one,
        else ``model_orders`` (1 for a model it does not name)."""
        return int(self.defaults.order or self.model_orders.get(model, 1))

    def resolve(self, params: Parameters) -> Parameters:
        """``params`` with ``order`` = 0 replaced by the case's order for its model."""
        if params.order or params.model == "auto":
            return params
        return dataclasses.replace(params, order=self.order_for(params.model))


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
    return get_case(info["case"])


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
    #: the netgen.occ shape the mesh was made from (None: a mesh file or structured quads)
    shape: object = None

    # -- schedules ----------------------------------------------------------------------------
    def apply_schedule(self, penal: float, beta: float, load: float) -> None:
        self.penal.Set(penal)
        for pr in self.projections:
            pr.beta = beta
        self.mech.target = load

    # -- evaluation -------------------------------------------------------------------------------
    def evaluate(self, x: np.ndarray, gradients: bool = True):
        """Return ``f0, fvals`` and, with ``gradients``, ``df0, dfvals`` (shape (m, n))."""
        vals = self.chain.forward(x=x)
        f0 = float(vals[self.objective])
        f = np.array([vals[c] for c in self.constraints], dtype=float)
        if not gradients:
            return f0, f
        df0 = np.asarray(self.chain.gradient(self.objective))
        df = np.array([np.asarray(self.chain.gradient(c)) for c in self.constraints])
        return f0, f, df0, df

    @property
    def values(self) -> dict:
        return self.chain.values

    def volume_fraction(self) -> float:
        vol = next(b for b in self.chain.blocks if b.output == "volume")
        return vol.fraction(self.values[vol.inputs[0]])


def domain_size(params: Parameters, width: float, height: float) -> tuple[float, float]:
    """``(width, height)``, or ``(nelx, nely)`` with ``unit_elements`` (1 x 1 elements, the
    set-up of the classic MATLAB codes)."""
    if params.unit_elements:
        return float(params.nelx), float(params.nely)
    return width, height


def mesh_for(case: Case, params: Parameters):
    """The case's meshed domain (:class:`~pacto_ng.geometry.Meshed`): Netgen triangles of size
    maxh, or structured quads if nelx > 0 (rectangular layouts only)."""
    from .geometry import mesh_geometry

    return mesh_geometry(case.make_geometry(params), maxh=params.maxh, nelx=params.nelx,
                         nely=params.nely)


def build_problem(case: Case, params: Parameters) -> Problem:
    """Mesh, design field, filter, projection, [Darcy], mechanics and responses as a chain."""
    from ngsolve import Parameter

    from . import responses as R
    from .design import DesignField, Embed, FixPassive
    from .filters import ConeFilter, HeavisideProjection, HelmholtzFilter, IdentityFilter
    from .physics.mechanics import Field, Mechanics
    from .physics.newton import NewtonSettings

    if case.analysis_only:
        raise InputError(f"case '{case.name}' is an analysis, not an optimisation")
    params = case.resolve(params)
    if params.model == "auto":
        raise InputError("model: 'auto' is chosen by 'pacto run' (pacto_ng.auto.choose_model), "
                         "not by build_problem")
    meshed = mesh_for(case, params)
    mesh, h = meshed.mesh, meshed.h
    setup = case.make_setup(params)
    from .geometry import check_inlet_touches_design, check_setup_names, check_vectors

    check_setup_names(mesh, setup)
    check_vectors(mesh, setup)
    if setup.pressure is not None:
        check_inlet_touches_design(mesh, setup.pressure.inlet, setup.void)
    try:
        field_ = DesignField(mesh, solid=setup.solid, void=setup.void)
    except ValueError as err:
        raise InputError(str(err)) from None
    radius = params.filter_radius or 3.0 * h
    nf = setup.materials
    names = ["rho_bar"] if nf == 1 else ["rho_bar1", "rho_bar2"]
    blocks, projections = [], []
    if nf == 2:
        blocks += [_Slice(field_.n, 0, "x1"), _Slice(field_.n, 1, "x2")]
    for i, out in enumerate(names):
        suf = "" if nf == 1 else str(i + 1)
        xin = "x" if nf == 1 else f"x{suf}"
        blocks.append(Embed(field_, inputs=(xin,), output=f"rho{suf}"))
        if params.filter == "helmholtz":
            flt = HelmholtzFilter(mesh, radius, inputs=(f"rho{suf}",), output=f"rho_tilde{suf}")
        elif params.filter == "cone":
            flt = ConeFilter(field_.centroids(), field_.areas, radius, inputs=(f"rho{suf}",),
                             output=f"rho_tilde{suf}")
        else:
            flt = IdentityFilter(inputs=(f"rho{suf}",), output=f"rho_tilde{suf}")
        blocks.append(flt)
        pr = HeavisideProjection(params.beta, params.eta, inputs=(f"rho_tilde{suf}",),
                                 output=f"rho_proj{suf}")
        projections.append(pr)
        blocks.append(pr)
        blocks.append(FixPassive(field_, inputs=(f"rho_proj{suf}",), output=out))
    penal = Parameter(params.penal)
    from .physics.energy import make_energy

    energy, guard, linear = make_energy(params, penal, tuple(names))
    mech_fields = list(names)
    body = None
    follower = None  # residual density of a follower Darcy load (SPEC §4)
    if params.load_type == "follower" and setup.pressure is None:
        raise InputError(f"load_type: case '{case.name}' has no pressure load to follow the deformation")
    pressure_block = None
    if params.inlet and setup.pressure is None:
        raise InputError(f"inlet: case '{case.name}' has no pressure load")
    if setup.pressure is not None:
        from .physics import darcy

        if params.delta_s < 0.1 * h:
            raise InputError(f"delta_s: {params.delta_s:g} is below a tenth of the element size "
                             f"{h:g} (set delta_s in the units of the mesh)")
        pressure = setup.pressure
        if params.inlet:
            pressure = Pressure(inlet=tuple(params.inlet.split("|")), zero=pressure.zero)
        try:
            # Wang: the follower load sees the deformation I + γ∇u of the energy's
            # large-strain part (void: the fixed load), unless follower_wang=0
            gamma = energy.gamma if params.model == "wang" and params.follower_wang else None
            pressure_block, pfield, body = darcy.for_case(mesh, params, pressure, names[0],
                                                          order=params.order, gamma=gamma)
        except ValueError as err:
            raise InputError(str(err)) from None
        if params.load_type == "follower":
            # -cof(F)∇p: a residual term (unsymmetric tangent, transposed adjoint).  It is
            # affine in u in 2D, so a linear material keeps its one-step linear solve.
            follower, body = body, None
        blocks.append(pressure_block)
        mech_fields.append(pfield)
    loads = tuple(PointLoad(ld.region, tuple(params.load * np.asarray(ld.force))) for ld in setup.loads)
    newton = NewtonSettings(rtol=params.newton_rtol, max_iter=params.newton_max_iter,
                            initial_increment=params.newton_increment,
                            min_increment=params.newton_min_increment)
    try:
        mech = Mechanics(mesh, order=params.order, energy=energy, fields=mech_fields,
                         supports=setup.supports, loads=loads, springs=setup.all_springs, body=body,
                         thickness=params.thickness, guard=guard, linear=linear, newton=newton,
                         residual_density=follower, realcompile=params.realcompile)
    except ValueError as err:
        raise InputError(str(err)) from None
    blocks.append(mech)
    reports = []
    obj = setup.objective if not params.objective else params.objective
    if obj not in OBJECTIVES:
        raise InputError(f"objective: must be one of {', '.join(OBJECTIVES)} (got '{obj}')")
    if obj == "compliance":
        if follower is not None:
            raise InputError("objective: compliance is not defined for a follower load (the load "
                             "vector depends on u); use energy, mechanism, output or output_se")
        if body is not None:
            blocks.append(darcy.Compliance(mech, pressure_block))
        else:
            blocks.append(R.compliance(mech))
        objective = "compliance"
    elif obj == "energy":
        blocks.append(R.StrainEnergy(mech))
        objective = "se"
    else:
        if not setup.ports:
            raise InputError(f"objective '{obj}' needs an output port")
        blocks.append(R.output_displacement(mech, setup.output))
        reports.append("delta")
        if obj == "output":
            blocks.append(R.Scale(-1.0, ("delta",), "objective"))
        elif obj == "output_se":  # max Δ subject to SE <= se_max
            se_max = params.se_max or setup.se_max
            if not se_max > 0:
                raise InputError(f"se_max: objective output_se needs a positive limit (case "
                                 f"'{case.name}' has no default; --set se_max=...)")
            blocks.append(R.Scale(-1.0, ("delta",), "objective"))
            blocks.append(R.StrainEnergy(mech))
            blocks.append(_Bound(se_max, ("se",), "se_limit"))
            reports.append("se")
        else:
            blocks.append(R.StrainEnergy(mech))
            blocks.append(R.MechanismRatio())
            reports.append("se")
        objective = "objective"
    for i, out in enumerate(names):
        vf = params.volfrac if i == 0 else params.volfrac2
        if i == 0 or params.volfrac2 > 0:
            blocks.append(R.Volume(field_, vf, inputs=(out,), output="volume" if i == 0 else "volume2"))
    constraints = ["volume"] + (["volume2"] if nf == 2 and params.volfrac2 > 0 else [])
    if obj == "output_se":
        constraints.append("se_limit")
    chain = Chain(blocks, inputs=("x",))
    return Problem(case, params, mesh, field_, chain, objective, constraints, mech, projections,
                   penal, setup, h, reports, pressure_block, nf, shape=meshed.shape)


class _Bound:
    """Block ``a -> a / bound - 1`` (a constraint ``a <= bound`` in the form ``g <= 0``)."""

    def __init__(self, bound, inputs, output):
        self.bound, self.inputs, self.output = float(bound), tuple(inputs), output

    def forward(self, a):
        return float(a) / self.bound - 1.0

    def backward(self, g):
        return (g / self.bound,)


class _Slice:
    """Block ``x -> x_i``: the i-th of several stacked design fields of n variables each."""

    def __init__(self, n, i, output):
        self.n, self.i = n, i
        self.inputs, self.output = ("x",), output

    def forward(self, x):
        return np.asarray(x)[self.i * self.n:(self.i + 1) * self.n].copy()

    def backward(self, g):
        self._full = np.zeros(2 * self.n)
        self._full[self.i * self.n:(self.i + 1) * self.n] = g
        return (self._full,)
