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

from .builders import Builder, standard_chain
from .derive import MECHANISM_RATIO, derive_settings, domain_size
from .errors import InputError
from .geometry_kinds import bounding_sides
from .meshing import mesh_geometry
from .parallel import DesignNumbering, distribute
from .params import Parameters
from .problem import Problem
from .robust import robust_chain
from .setup import Pressure, Setup  # noqa: F401 - Pressure: pacto_ng.case.Pressure for scripts
from .setup_names import check_inlet_touches_design, check_setup_names, check_vectors

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
    #: through this): the knee of the case's trade curve (docs/studies.md)
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
        # ... and before the forms chose their compilation (2026-12-06) realcompile was
        # true / false: on (1) / off (0), as those runs ran
        if isinstance(values.get("realcompile"), bool):
            values = dict(values, realcompile=int(values["realcompile"]))
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


def mesh_for(case: Case, params: Parameters):
    """The case's meshed domain (:class:`~pacto_ng.mesh.Meshed`): Netgen triangles or
    tetrahedra of size maxh, or structured quads (hexahedra) if nelx > 0 (a Layout; a Box with
    nelz)."""
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
    (:class:`~pacto_ng.mesh.Meshed`, e.g. a run's, to analyse its design at another
    order on the same elements)."""
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
    failure = None
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
        meshed, numbering = distribute(meshed, comm)

    builder = Builder(case, params, meshed, setup)
    if params.robust:
        if case.chain is not standard_chain:
            raise InputError(f"robust: case '{case.name}' builds its own chain; the robust "
                             "formulation replaces the standard chain only")
        problem = robust_chain(builder)
    else:
        problem = case.make_problem(builder)
    if numbering is not None:
        problem.numbering = numbering
        problem.design_numbering = DesignNumbering(numbering, problem.field)
    return problem
