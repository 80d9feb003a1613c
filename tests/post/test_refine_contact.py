"""A part whose walls meet: the run's part stage analyses it with them in contact, and
``pacto refine DIR --contact`` refines it so (pacto_ng/shape/contact_term.py; the gradient's
check: tests/shape/test_contact_gradient.py).

The run: tests/post/cases/slotted_block.py at 3 kPa, two iterations from a design of volume
fraction 0.95 (its part is the slotted block).  The slot's walls meet under that pressure:
with contact the part as made moves less than without (the closed slot carries the load),
and the refinement, which sees the contact, opens the slot's mouth (measured: Δ 0.01254 ->
0.03047 m in 3 steps, 0.0293 m in one; without contact the part moves 0.02964 m)."""
import json
from pathlib import Path

import pytest

from pacto_ng.cli import main
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.physics.walls import solid_boundaries
from pacto_ng.post.part_analysis import PartAnalysis
from pacto_ng.post.part_stage import _overlap_warning, _with_contact, walls_probe
from contact_parts import slotted_block, slotted_slab

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

CASE = Path(__file__).parent / "cases" / "slotted_block.py"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("slotted") / "run"
    assert main(["run", str(CASE), "--iterations", "2", "--set", "volfrac=0.95", "--set",
                 "delta_s=0.05", "--load", "3000", "--no-refine", "--out", str(out),
                 "--quiet"]) == 0
    return out


def test_the_run_analyses_its_part_with_the_walls_in_contact_where_they_meet(run):
    """The run's part stage finds the slot's walls passing through each other at 3 kPa and
    analyses the 2D part again with them in contact: those are the part's figures."""
    part = json.loads((run / "summary.json").read_text())["part"]
    touch = part["contact"]
    assert touch["overlap_without"] > 0.1 and touch["analysed"] and touch["converged"]
    assert part["output_displacement"] < 0.6 * touch["output_displacement_without"]


def test_the_refinement_with_contact_sees_the_walls_touch(run):
    assert main(["refine", str(run), "--contact", "--steps", "1", "--quiet"]) == 0
    refined = json.loads((run / "refine" / "summary.json").read_text())
    # the run's own analysis of its part, with contact, at the same pressure and order
    part = json.loads((run / "summary.json").read_text())["part"]
    assert refined["part"]["contact"] and part["order"] == refined["part"]["order"]
    assert refined["delta_before"] == pytest.approx(part["output_displacement"], rel=1e-6)
    assert refined["delta_after"] > 2.0 * refined["delta_before"]  # the slot's mouth opened


@pytest.mark.parametrize("formulation", ["displacement", "mixed"])
def test_the_walls_overlap_is_measured_on_the_displacement(formulation):
    """The walls' probe reads the displacement of either formulation (the mixed state holds
    (u, ϑ, p̃)): the slotted block's walls overlap at 3 kPa and not at 300 Pa."""
    mesh = slotted_block(0.1)
    params = Parameters(model="neohookean", E1=1e6, E0=1.0, nu=0.45, plane="strain",
                        thickness=1.0, formulation=formulation)
    ana = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("left",)),
                       ports=Port("corner", (0.0, -1.0)), boundary="pressure", order=2)
    assert ana.formulation == formulation
    overlaps = []
    for pressure in (300.0, 3000.0):
        assert ana.solve(pressure).converged
        overlaps.append(walls_probe(ana, solid_boundaries(mesh)).overlap(ana.mech.u.vec))
    assert overlaps[0] == 0.0 and overlaps[1] > 0.1


@pytest.mark.slow  # 20-40 s: the default suite stays under 10 minutes
def test_a_3d_part_s_walls_are_probed_and_the_part_analysed_with_them_in_contact():
    """A 3D part's walls are probed at one point per face (part_stage.PROBE_INTORDER_3D): the
    slotted slab's overlap at 3 kPa within 15 % of the contact quadrature's (11 % on these
    1213 tetrahedra, 5 % at half their size, measured 2026-12-06), none at 500 Pa.  Where
    they pass through each other the part is analysed again with every wall in contact, as a
    2D part is, once one Newton iteration with contact is timed (here at order 1, to be
    quick): the slot then stays shut to the penalty's overlap and the corner moves less."""
    from types import SimpleNamespace

    from pacto_ng.physics.contact import SelfContact
    from pacto_ng.post.part_analysis import CONTACT_REACH
    from pacto_ng.setup import Setup

    mesh = slotted_slab(0.1)
    params = Parameters(model="linear", E1=1e6, E0=1.0, nu=0.3, order=2)
    supports = Supports(clamp=("left",), fix_z=("front", "back"))
    port = Port("corner", (0.0, -1.0, 0.0))
    ana = PartAnalysis(mesh, "fixed", params=params, supports=supports, ports=port)
    walls = solid_boundaries(mesh)
    assert ana.solve(500.0).converged and walls_probe(ana, walls).overlap(ana.mech.u.vec) == 0
    point = ana.solve(3000.0)
    found = walls_probe(ana, walls).overlap(ana.mech.u.vec)
    full = SelfContact.on_walls(ana.mech.u.space, walls, modulus=1.0, penalty=1.0,
                                reach=CONTACT_REACH).overlap(ana.mech.u.vec)
    assert full > 0.05 and found == pytest.approx(full, rel=0.15)
    area, depth = walls_probe(ana, walls).overlap_depth(ana.mech.u.vec)
    assert area == found
    assert depth > 0.2 * point.max_u  # passing through each other, not touching as made
    said = []
    problem = SimpleNamespace(params=params, setup=Setup(supports=supports, port=port),
                              case=SimpleNamespace(load_unit="Pa"))
    entry, (again, touching) = _with_contact(SimpleNamespace(mesh=mesh, dim=3), problem,
                                             (ana, point), (3000.0, "fixed", 1), said.append)
    assert entry["analysed"] and entry["converged"] and entry["overlap_without"] == found
    assert said[0].startswith(f"its walls pass through each other there (overlap {found:.3g}"
                              f" m²): analysed again with them in contact (")
    assert again is not ana and touching.converged and touching.contact_area > 0
    apart = PartAnalysis(mesh, "fixed", params=params.replace(order=1), supports=supports,
                         ports=port).solve(3000.0)  # at the order analysed in contact
    assert touching.delta < 0.9 * apart.delta  # the closed slot carries load
    assert walls_probe(again, walls).overlap_depth(again.mech.u.vec)[1] < 1e-3 * depth
    assert _overlap_warning(entry, "DIR") == []


def test_a_part_whose_contact_analysis_would_take_too_long_says_what_it_would_take():
    entry = {"overlap_without": 0.0875, "analysed": False, "estimate": "2.1 h to 24 h"}
    warning, = _overlap_warning(entry, "DIR")
    assert "not analysed in contact (it would take 2.1 h to 24 h): 'pacto analyse DIR " \
           "--contact --time-limit S' does" in warning
