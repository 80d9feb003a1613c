"""Contact past a pressure maximum: a shallow arch pressed through its snap onto the floor
plate under it (tests/contact_parts.py, ``pressed_arch``; Neo-Hookean, E = 1 MPa, plane
strain, order 2, half the arch with its symmetry line held).

The arch's pressure rises to a maximum, then falls as the arch snaps down, until its crown
lands on the plate and the pressure climbs again.  A sweep of the part's analysis
(:meth:`pacto_ng.post.part_analysis.PartAnalysis.sweep`) loses the equilibrium at the
maximum, follows the path with the crown's motion prescribed (its pairs sought anew at each
point, pacto_ng/physics/path.py), past the valley where the crown comes to rest, and Newton
ramps on from there.  Without contact the same sweep jumps through the plate to the inverted
arch."""
import pytest

from contact_parts import FLOOR, RISE, pressed_arch
from pacto_ng import Parameters, Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.physics.path import load_maximum, trace
from pacto_ng.post.part_analysis import PartAnalysis


@pytest.fixture(scope="module")
def mesh():
    return pressed_arch()


def analysis(mesh, contact=()):
    params = Parameters(model="neohookean", E1=1e6, E0=1.0, nu=0.3, plane="strain",
                        thickness=1.0, order=2)
    return PartAnalysis(mesh, "fixed", params=params,
                        supports=Supports(clamp=("fixed",), fix_x=("sym",)),
                        ports=Port("crown", (0.0, -1.0)), contact=contact)


def crown_gap(mesh, an) -> float:
    """The gap between the arch's inner wall and the plate's top on the symmetry line."""
    u = an.mech.u
    return (FLOOR + RISE + u(mesh(0.5, FLOOR + RISE))[1]) - (FLOOR + u(mesh(0.5, FLOOR))[1])


def test_an_arch_pressed_past_its_snap_lands_on_the_plate(mesh, one_thread):
    """With contact: every pressure converges, the maximum the sweep reports is the one the
    path without contact passes (the snap comes before the walls touch: the crown has moved
    0.03 of its 0.08 m rise there), the crown rests on the plate within the penalty's
    overlap, and the contact spreads as the pressure grows.  Without contact the arch passes
    through the plate."""
    free = analysis(mesh)
    mech = free.mech
    mech.set_fields(*free.solid_values())
    path = trace(mech, mech.gfx.vec, free.output_form, 0.0025, mech.settings,
                 stop=lambda q: q.control >= 0.04, max_step=0.0025, max_points=40)
    top = load_maximum(path)
    assert top is not None and 0.02 < top[0] < 0.04  # Δ at the maximum, before contact
    paired = analysis(mesh, ("slot",))  # the same path with contact, from rest (no pairs yet)
    paired.mech.set_fields(*paired.solid_values())
    same = trace(paired.mech, paired.mech.gfx.vec, paired.output_form, 0.0025,
                 paired.mech.settings, stop=lambda q: q.control >= 0.04, max_step=0.0025,
                 max_points=40)
    assert load_maximum(same) == pytest.approx(top, rel=1e-8)

    lines = []
    pressed = analysis(mesh, ("slot",))
    sweep = pressed.sweep([100.0, 300.0, 1000.0], say=lines.append)
    assert [p.converged for p in sweep.points] == [True, True, True]
    assert sweep.points[1].past_peak and any("a pressure maximum" in ln for ln in lines)
    # measured: 193.32 Pa at Δ = 0.02934 against the path's 193.14 Pa at 0.02933 (steps of
    # 0.0025; 193.11 and 193.15 Pa with steps twice and half as long)
    assert sweep.peak["pressure"] == pytest.approx(top[1], rel=2e-3)
    assert sweep.peak["delta"] == pytest.approx(top[0], rel=0.05)
    assert crown_gap(mesh, pressed) > -1e-3 * RISE  # on the plate, not through it
    areas = [p.contact_area for p in sweep.points]
    assert areas[0] == 0.0 and 0.0 < areas[1] < areas[2]
    assert all(p.delta == pytest.approx(RISE, rel=0.01) for p in sweep.points[1:])

    through = analysis(mesh)
    assert all(p.converged for p in through.sweep([100.0, 300.0]).points)
    assert crown_gap(mesh, through) < -0.5 * RISE
