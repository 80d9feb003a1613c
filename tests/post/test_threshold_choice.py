"""Choosing the threshold (pacto_ng.post.threshold_choice): volume-preserving, and lowered until the part
kept on the clamp contains the output point.

Closed forms on the 100 x 50 structured chamber mesh (h = 1 mm, domain 0.1 x 0.05 m):
* ρ = (x/W)² per element (centroid x): the design's material volume is W H / 3 (to O(h²)), the
  nodal density at an interior vertex is x²/W² to O(h²), so the solid {ρ ≥ t} has area
  (1 - √t) W H and the volume-preserving threshold is t = 4/9;
* a solid block on the clamp with a grey (ρ = 0.3) bar out to the output point: the point's
  nodal density is 0.3 (it lies inside the bar), so the largest threshold at which the part on
  the clamp contains it is 0.3.
"""
import numpy as np
import pytest

from conftest import H, W, box_density, chamber_density
from pacto_ng.post.threshold import threshold
from pacto_ng.post.threshold_choice import (choose_threshold, connecting_threshold, design_volume,
                                            part_contains, volume_threshold)


def _centroids(mesh):
    from pacto_ng.post.grid import mesh_to_pyvista

    return np.asarray(mesh_to_pyvista(mesh).cell_centers().points)[:, :2]


def test_volume_threshold_of_a_quadratic_grading(chamber_quads):
    rho = (_centroids(chamber_quads)[:, 0] / W) ** 2
    assert design_volume(chamber_quads, rho) == pytest.approx(W * H / 3.0, rel=1e-4)
    t = volume_threshold(chamber_quads, rho)
    assert t == pytest.approx(4.0 / 9.0, abs=2e-3)
    # and at that threshold the part has the design's volume (the bisection's own test)
    assert threshold(chamber_quads, rho, t).area == pytest.approx(W * H / 3.0, rel=1e-3)


def test_volume_threshold_of_a_crisp_design_keeps_its_area(chamber_quads):
    rho = chamber_density(chamber_quads)
    t = volume_threshold(chamber_quads, rho)
    assert threshold(chamber_quads, rho, t).area == pytest.approx(
        design_volume(chamber_quads, rho), rel=1e-4)
    # a 0/1 design aligned with the elements: the 0.5 cut has the frame's area + h² (the
    # corners, see test_threshold.py), so the volume-preserving cut lies just above 0.5
    assert 0.5 < t < 0.55


def test_volume_threshold_without_material_raises(chamber_quads):
    with pytest.raises(ValueError, match="no material"):
        volume_threshold(chamber_quads, np.zeros(chamber_quads.ne))


def test_part_contains_frame_hole_and_outside(chamber_quads):
    th = threshold(chamber_quads, chamber_density(chamber_quads))
    assert part_contains(th, (0.05, 0.01))  # in the bottom wall
    assert part_contains(th, (0.0, 0.02))  # on the clamp edge (the boundary counts)
    assert part_contains(th, (0.05, 0.005))  # on the wall's outer face
    assert not part_contains(th, (0.05, 0.0225))  # in the cavity (a hole)
    assert not part_contains(th, (0.095, 0.045))  # void outside the frame
    assert not part_contains(th, (0.05, 0.01), clamp=("inlet",))  # the piece is on 'fixed'


BLOCK = (0.0, 0.0, 0.03, 0.05)  # solid, on the clamp (x = 0)
BAR = (0.03, 0.0, 0.06, 0.012)  # grey 0.3, from the block to the output point
POINT = (0.05, 0.005)


def _grey_bar(mesh):
    return box_density(mesh, [BLOCK]) + 0.3 * box_density(mesh, [BAR])


def test_connecting_threshold_finds_the_grey_joint(chamber_quads):
    rho = _grey_bar(chamber_quads)
    assert not part_contains(threshold(chamber_quads, rho, 0.5), POINT)
    t, th = connecting_threshold(chamber_quads, rho, 0.5, POINT)
    assert 0.3 - 0.005 <= t <= 0.3
    assert th.threshold == t and part_contains(th, POINT)
    assert not part_contains(threshold(chamber_quads, rho, 0.3 + 0.002), POINT)


def test_connecting_threshold_keeps_a_connected_start(chamber_quads):
    rho = chamber_density(chamber_quads)
    t, th = connecting_threshold(chamber_quads, rho, 0.5, (0.05, 0.005))
    assert t == 0.5 and th.threshold == 0.5


def test_connecting_threshold_gives_up_below_the_floor(chamber_quads):
    rho = _grey_bar(chamber_quads)
    t, th = connecting_threshold(chamber_quads, rho, 0.5, (0.09, 0.045))  # void everywhere
    assert t is None and th.threshold == 0.5
    t, _ = connecting_threshold(chamber_quads, rho, 0.5, POINT, floor=0.35)
    assert t is None


def test_choose_threshold_lowers_to_the_output_and_records_why(chamber_quads):
    """What ``pacto analyse`` uses: the chamber layout's named point 'output' is POINT."""
    from conftest import OUTPUT

    assert OUTPUT == POINT
    rho = _grey_bar(chamber_quads)
    ch, th = choose_threshold(chamber_quads, rho, 0.5, ["output"], ("fixed",))
    assert th.threshold == ch["used"]
    assert ch["lowered"] and ch["reaches_output"] and not ch["missed"]
    assert ch["start"] == 0.5 and 0.295 <= ch["used"] <= 0.3
    assert "lowered to" in ch["note"]
    assert ch["design_volume"] == pytest.approx(0.03 * 0.05 + 0.3 * 0.03 * 0.012, rel=1e-9)
    assert ch["part_area"] == pytest.approx(threshold(chamber_quads, rho, ch["used"]).area)
    kept, _ = choose_threshold(chamber_quads, rho, 0.5, ["output"], ("fixed",), connect=False)
    assert kept["used"] == 0.5 and not kept["lowered"] and kept["reaches_output"] is False
    vol, _ = choose_threshold(chamber_quads, chamber_density(chamber_quads), "volume", ["output"],
                              ("fixed",))
    # the volume-preserving cut lies just above 0.5 (see above), and the output point on the
    # wall's outer face has the nodal density 1/2: the threshold comes down to it
    assert vol["requested"] == "volume" and 0.5 < vol["start"] < 0.55
    assert vol["lowered"] and 0.495 <= vol["used"] <= 0.5
    assert threshold(chamber_quads, chamber_density(chamber_quads), vol["start"]).area \
        == pytest.approx(vol["design_volume"], rel=1e-4)


@pytest.mark.parametrize("value, ok", [("volume", "volume"), ("0.4", 0.4), (0.3, 0.3)])
def test_check_threshold_accepts(value, ok):
    from pacto_ng.post.cli_commands import check_threshold

    assert check_threshold(value, allow_volume=True) == ok


@pytest.mark.parametrize("value", ["half", "1.2", "0"])
def test_check_threshold_rejects_with_the_option_named(value):
    from pacto_ng.params import InputError
    from pacto_ng.post.cli_commands import check_threshold

    with pytest.raises(InputError, match="--threshold"):
        check_threshold(value, allow_volume=True)
    with pytest.raises(InputError, match="--threshold"):
        check_threshold("volume")  # export: a number only


@pytest.mark.parametrize("rebuilt, summary, warned", [
    (5.1e-4, 5.1e-4 * (1 + 1e-6), False), (3.2e-5, 5.1e-4, True), (None, 5.1e-4, False),
    (1e-3, None, False), (-2e-5, 2e-5, True)])
def test_load_path_note(rebuilt, summary, warned):
    """A Δ of the final design loaded from rest that is not the optimisation's (measured on a
    PneuNet design at 1e6 Pa: 3.2e-5 and 7.3e-5 m from rest, 5.1e-4 m in summary.json)."""
    from pacto_ng.post.expected import load_path_note

    note = load_path_note(rebuilt, summary)
    assert (note is not None) == warned
    if warned:
        assert "depends on the load path" in note and f"{rebuilt:.4g}" in note


def test_an_output_port_on_a_boundary_lowers_the_threshold_until_the_part_reaches_it():
    """A port on an edge (its mean is read) is checked too (post.part.reach_boundary_ports):
    a solid block on the clamp with a grey (ρ = 0.3) bar out to the right edge ``tip``, the
    port: the edge's vertices have the nodal density 0.3, so the part on the clamp touches
    the edge from threshold 0.3 down; at 0.5 it does not (and with --keep-threshold the
    record says so)."""
    from pacto_ng.mesh import Layout, Segment, structured_mesh
    from pacto_ng.post.part import reach_boundary_ports

    layout = Layout(W, H, segments=(Segment("fixed", (0.0, H), (0.0, 0.0)),
                                    Segment("tip", (W, 0.0), (W, H))))
    mesh = structured_mesh(layout, 40, 20)
    rho = box_density(mesh, [(0.0, 0.01, 0.09, 0.04)]) \
        + 0.3 * box_density(mesh, [(0.09, 0.01, W, 0.04)])
    choice, th = choose_threshold(mesh, rho, 0.5, ["tip"], ("fixed",))
    assert choice["reaches_output"] is None  # no named point: choose_threshold checks none
    th = reach_boundary_ports(mesh, rho, choice, th, ["tip"], ("fixed",))
    assert 0.295 <= choice["used"] <= 0.3 and choice["lowered"]
    assert choice["boundary_ports"] == {"tip": True} and choice["reaches_output"] is True
    assert "'tip'" in choice["note"] and th.threshold == choice["used"]
    assert any("tip" in c.names and "fixed" in c.names for c in th.components)
    kept, th = choose_threshold(mesh, rho, 0.5, ["tip"], ("fixed",), connect=False)
    th = reach_boundary_ports(mesh, rho, kept, th, ["tip"], ("fixed",), connect=False)
    assert kept["used"] == 0.5 and kept["boundary_ports"] == {"tip": False}
    assert kept["reaches_output"] is False and "--keep-threshold" in kept["note"]
