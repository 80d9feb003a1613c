"""The API reference (docs/api.md): pdoc builds it from the docstrings without a warning, and
every public name has a docstring of its own.

pdoc is not a dependency of the package; the test is skipped where it is not installed
(``pip install pdoc``, or the ``test`` extra once it lists ``pdoc>=14``).
"""
from __future__ import annotations

import dataclasses
import importlib
import inspect
import logging
import warnings

import pytest

import pacto_ng

#: the modules of the reference, as docs/api.md builds them (pacto_ng: the public API of
#: ``__all__``; the others: where those names live, with their module docstrings)
MODULES = ["pacto_ng", "pacto_ng.api", "pacto_ng.case", "pacto_ng.setup", "pacto_ng.problem",
           "pacto_ng.errors", "pacto_ng.geometry", "pacto_ng.meshing", "pacto_ng.setup_names",
           "pacto_ng.mesh",
           "pacto_ng.settings", "pacto_ng.builders",
           "pacto_ng.params", "pacto_ng.physics.loads", "pacto_ng.post"]

#: the public names that are not functions or classes (no docstring of their own)
DATA = {"__version__"}

#: public names known to lack a docstring of their own (dataclasses that only have the
#: generated signature), with their file; strict: the test fails once one is written, and its
#: entry here is then to be removed
UNDOCUMENTED: dict = {}  # public names known to lack a docstring (none)


def own_docstring(obj) -> str:
    """``obj``'s docstring, or "" when it has none of its own: a dataclass without one gets
    ``Name(field: type, ...)`` from ``dataclasses`` (``inspect.getdoc`` returns that)."""
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj) and dataclasses.is_dataclass(obj) and \
            doc.startswith(f"{obj.__name__}("):
        return ""
    return doc.strip()


@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=f"no docstring yet "
                                            f"({UNDOCUMENTED[n]})"))
    if n in UNDOCUMENTED else n
    for n in pacto_ng.__all__ if n not in DATA])
def test_every_public_name_has_a_docstring(name):
    obj = getattr(pacto_ng, name)
    assert inspect.getdoc(obj), f"pacto_ng.{name} has no docstring"
    assert own_docstring(obj), (f"pacto_ng.{name} ({inspect.getsourcefile(obj)}) has no "
                                f"docstring of its own (only the dataclass signature)")


def test_pn_run_stays_the_function():
    """``pacto_ng.run`` is the function ``pacto_ng.api.run`` even after every submodule is
    imported (pdoc imports them all; a submodule ``pacto_ng/run.py`` would replace the
    attribute by the module on its first import)."""
    for mod in MODULES:
        importlib.import_module(mod)
    import pkgutil

    for info in pkgutil.iter_modules(pacto_ng.__path__):
        assert info.name not in pacto_ng.__all__, (
            f"submodule pacto_ng.{info.name} has the name of a public API member: importing "
            f"it replaces pacto_ng.{info.name}")
    assert pacto_ng.run is pacto_ng.api.run


def test_pdoc_builds_the_reference_without_warnings(tmp_path, caplog):
    pdoc = pytest.importorskip("pdoc", reason="pdoc builds the API reference (pip install pdoc; "
                                              "docs/api.md)")
    import pdoc.render

    for mod in MODULES:  # import-time warnings of the dependencies are not pdoc's
        importlib.import_module(mod)
    pdoc.render.configure(docformat="numpy")
    with warnings.catch_warnings(record=True) as caught, caplog.at_level(logging.WARNING):
        warnings.simplefilter("always")
        pdoc.pdoc(*MODULES, output_directory=tmp_path)
    emitted = [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in caught]
    emitted += [f"log {r.name}: {r.getMessage()}" for r in caplog.records]
    assert not emitted, "pdoc warned:\n" + "\n".join(emitted)

    index = (tmp_path / "pacto_ng.html").read_text()
    for name in pacto_ng.__all__:
        if name not in DATA:
            assert f'id="{name}"' in index, f"pacto_ng.{name} is missing from the reference"
    for mod in MODULES[1:]:
        assert (tmp_path / (mod.replace(".", "/") + ".html")).is_file(), mod
    # the numpydoc sections are rendered, not shown as text
    api = (tmp_path / "pacto_ng" / "api.html").read_text()
    assert "Optimise a case" in api and "<h6" in api and "Raises" in api
