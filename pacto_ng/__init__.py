"""pacto_ng — NGSolve-based topology optimisation of pressure-actuated soft robots and
compliant mechanisms."""
import importlib.util as _ilu
import os as _os
import sys as _sys

__version__ = "0.1.0"


def _source_subpackages():
    """The repository's top-level ``cases/`` and ``geometries/`` are installed as
    ``pacto_ng.cases`` and ``pacto_ng.geometries`` (pyproject package-dir).  When the package
    is imported from a source checkout instead (e.g. ``python -m pytest`` puts the checkout
    first on ``sys.path``), register those folders under the same names."""
    here = _os.path.dirname(_os.path.abspath(__file__))
    root = _os.path.dirname(here)
    for name in ("cases", "geometries"):
        full = f"{__name__}.{name}"
        src = _os.path.join(root, name)
        if full in _sys.modules or _os.path.isdir(_os.path.join(here, name)):
            continue
        init = _os.path.join(src, "__init__.py")
        if not _os.path.isfile(init):
            continue
        spec = _ilu.spec_from_file_location(full, init, submodule_search_locations=[src])
        module = _ilu.module_from_spec(spec)
        _sys.modules[full] = module
        spec.loader.exec_module(module)


_source_subpackages()

# -- the public API: what a case file, a script or a notebook uses ------------------------------
from .errors import InputError  # noqa: E402
from .params import Parameters  # noqa: E402
from .settings import Settings, setting  # noqa: E402
from .physics.loads import Outputs, PointLoad, Port, Spring  # noqa: E402
from .physics.mechanics import Supports  # noqa: E402
from .mesh import Layout, Region, Segment  # noqa: E402
from .box import Block, Box, Patch  # noqa: E402
from .setup import Pressure, Setup  # noqa: E402
from .problem import Problem  # noqa: E402
from .case import Case, domain_size, get_case, load_case_file  # noqa: E402
from .builders import Builder, Responses, standard_chain  # noqa: E402
from .responses import StrainEnergy, output_displacement  # noqa: E402
from .geometry import load_cad, load_mesh  # noqa: E402
from .meshing import mesh_geometry  # noqa: E402
from .api import Result, check_gradients, load_result, run  # noqa: E402


def main(argv=None) -> int:
    """The ``pacto`` command from Python: ``main(["run", "my_case.py", "--iterations", "50"])``
    returns its exit code (0 done, 1 stopped by a numerical failure, 2 bad input)."""
    from .cli import main as cli_main

    return cli_main(argv)


__all__ = [
    # a case
    "Case", "Setup", "Parameters", "Supports", "Pressure", "Port", "Outputs", "Spring",
    "PointLoad", "Settings", "setting", "domain_size",
    # its chain of blocks
    "Builder", "standard_chain", "Problem", "Responses", "output_displacement", "StrainEnergy",
    # geometry
    "Layout", "Segment", "Region", "Box", "Patch", "Block", "load_cad", "load_mesh", "mesh_geometry",
    # running
    "run", "Result", "load_result", "check_gradients", "get_case", "load_case_file", "InputError", "main",
    "__version__",
]
