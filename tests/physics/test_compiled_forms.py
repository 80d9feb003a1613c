"""Where a nonlinear model's Newton forms are compiled to machine code by themselves
(``realcompile`` = -1, :meth:`pacto_ng.physics.newton.NewtonParameters.compiles`): where the
elements times the Newton iterations expected reach ``COMPILE_PAYS`` and NGSolve's ``ngscxx``
is on PATH; 1 and 0 force it.  That compiled forms change nothing but the speed is
tests/physics/test_wang.py's ``test_realcompile_gives_the_same_residual_and_tangent``."""
import shutil

import numpy as np
import pytest

from pacto_ng.case import build_problem, get_case
from pacto_ng.physics.compiled import COMPILE_PAYS, COMPILE_PAYS_SYMBOLIC, element_weight
from pacto_ng.physics.newton import NewtonParameters


def test_the_forms_are_compiled_where_the_work_pays_for_the_compiler(monkeypatch):
    auto, on, off = (NewtonParameters(realcompile=v) for v in (-1, 1, 0))
    assert on.compiles(True, 1.0) and not off.compiles(False, 1e12)
    monkeypatch.setattr(shutil, "which", lambda name: "/bin/" + name)
    assert auto.compiles(False, COMPILE_PAYS) and not auto.compiles(False, 0.99 * COMPILE_PAYS)
    # the symbolic 3D tangent's compiled code is larger: it pays later
    assert COMPILE_PAYS_SYMBOLIC > COMPILE_PAYS
    assert not auto.compiles(False, 0.99 * COMPILE_PAYS_SYMBOLIC, symbolic=True)
    assert auto.compiles(False, COMPILE_PAYS_SYMBOLIC, symbolic=True)
    assert not auto.compiles(True, 1e12)  # a linear model has no Newton forms to speed up
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert not auto.compiles(False, 1e12)  # no compiler wrapper: not compiled
    assert on.compiles(False, 1.0)  # asked for: NGSolve says what is missing


def test_an_elements_work_counts_its_nodes_against_order_1():
    """The work weighs an element by its nodes at its order over its nodes at order 1: a
    tetrahedron has 4, 10 and 20 nodes at orders 1-3, a triangle 3 and 6, a quadrilateral 4
    and 9, a hexahedron 8 and 27."""
    assert element_weight(1, 3, True) == 1.0 and element_weight(1, 2, False) == 1.0
    assert element_weight(2, 3, True) == 10 / 4 and element_weight(3, 3, True) == 20 / 4
    assert element_weight(2, 2, True) == 6 / 3
    assert element_weight(2, 2, False) == 9 / 4 and element_weight(2, 3, False) == 27 / 8


@pytest.mark.skipif(shutil.which("ngscxx") is None, reason="needs NGSolve's ngscxx")
def test_a_long_nonlinear_run_compiles_its_forms_and_a_short_one_not():
    """pneunet-silicone (Wang, 2400 elements): 3 iterations are 2.9e4 element-Newton
    iterations, not compiled; its default 160 iterations 1.5e6, compiled."""
    case = get_case("pneunet-silicone")
    short = build_problem(case, case.resolve(case.defaults.replace(iterations=3)))
    assert short.mesh.ne == 2400 and not short.mech.realcompile
    long = build_problem(case, case.resolve(case.defaults))
    assert long.params.iterations == 160 and long.mech.realcompile


def test_without_a_compiler_the_forms_run_as_compiled_expressions(tmp_path, monkeypatch, capfd):
    """ngscxx on PATH but no C++ compiler behind it: one warning line, and the problem is
    built and solves as one built with the forms not compiled."""
    case = get_case("pneunet-silicone")
    params = case.resolve(case.defaults.replace(iterations=3))
    plain = build_problem(case, params.replace(realcompile=0))
    x = np.linspace(0.1, 0.9, plain.n_design)
    plain.chain.forward(x=x)
    fake = tmp_path / "bin"
    fake.mkdir()
    for name in ("ngscxx", "python3"):
        (fake / name).symlink_to(shutil.which(name))
    monkeypatch.setenv("PATH", str(fake))
    problem = build_problem(case, params.replace(realcompile=1))
    assert not problem.mech.realcompile
    assert capfd.readouterr().err.count("pacto: warning: the Newton forms are not compiled") == 1
    problem.chain.forward(x=x)
    key = problem.mech.output
    assert np.array_equal(problem.values[key].FV().NumPy(), plain.values[key].FV().NumPy())
