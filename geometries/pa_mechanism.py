"""Pressure-actuated inverter and gripper, half domain (symmetry at y = 0), docs/theory.md §6.

Boundaries: "inlet" (the left edge), "fixed" (the first ``clamp`` of the top edge, default
L/20, next to the left corner), "zero_pressure" (the rest of the top edge and the right edge),
"symmetry" (the bottom edge).  Passive solid "block" (``block`` = width x height, default
L/20 x H/20) under the clamp.  The gripper adds a passive void "jaw_void" (the gripped object's
place) over x ∈ [0.8L, L], y ∈ [0, 0.2H] and a passive solid "jaw_pad" over x ∈ [0.8L, L],
y ∈ [0.2H, 0.25H].  Port "output": the bottom-right corner (inverter) or the inner right corner
of the jaw pad (L, 0.2H) (gripper); with ``output_edge`` > 0 the right edge's first
``output_edge`` from that corner (upwards on the gripper's pad, at most its 0.05H) is a
boundary of its own, "output_edge", where the spring and the port act spread.  The cases put zero pressure on the whole top edge
(docs/theory.md §6, "pa-inverter"): they list "fixed" among the zero-pressure boundaries as
well.
"""
from pacto_ng.derive import mechanism_scales
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port, Spring
from pacto_ng.physics.mechanics import Supports
from pacto_ng.mesh import Layout, Region, Segment
from pacto_ng.setup import Pressure, Setup


def layout(width: float = 0.2, height: float = 0.1, clamp: float | None = None,
           block: tuple[float, float] | None = None, gripper: bool = False,
           output_edge: float = 0.0) -> Layout:
    """``output_edge`` > 0: the right edge's first ``output_edge`` from the output corner is a
    boundary of its own, "output_edge" (a spread output spring and port): upwards from
    (L, 0) on the inverter, shorter than the edge, and from (L, 0.2H) along the gripper's
    jaw pad, at most its height 0.05H (so that it lies on passive solid in the design and in
    its part alike)."""
    L, H = width, height
    clamp = L / 20 if clamp is None else clamp
    bw, bh = block if block is not None else (L / 20, H / 20)
    y0, room = (0.2 * H, 0.05 * H * (1 + 1e-12)) if gripper else (0.0, H * (1 - 1e-12))
    if output_edge and not 0.0 < output_edge <= room:
        raise ValueError(f"output_edge: {output_edge:g} is not in (0, {room:.6g}], the "
                         + ("jaw pad's right edge" if gripper else "right edge"))
    edge = ((Segment("output_edge", (L, y0), (L, y0 + output_edge)),) if output_edge
            else ())
    segments = (Segment("inlet", (0.0, H), (0.0, 0.0)),
                Segment("fixed", (0.0, H), (clamp, H)),
                Segment("zero_pressure", (clamp, H), (L, H))) + edge + (
                Segment("zero_pressure", (L, 0.0), (L, H)),
                Segment("symmetry", (0.0, 0.0), (L, 0.0)))
    regions = [Region("block", "solid", 0.0, H - bh, bw, H)]
    if gripper:
        regions += [Region("jaw_void", "void", 0.8 * L, 0.0, L, 0.2 * H),
                    Region("jaw_pad", "solid", 0.8 * L, 0.2 * H, L, 0.25 * H)]
        points = (("output", (L, 0.2 * H)),)
    else:
        points = (("output", (L, 0.0)),)
    return Layout(L, H, segments=segments, regions=tuple(regions), points=points)


def gripper_setup(p: Parameters, width: float = 0.2, height: float = 0.1,
                  output_edge: bool = False) -> Setup:
    """The gripper's set-up on its ``width`` x ``height`` half (geometries/pa_mechanism.py's
    layout with ``gripper=True``): the set-up of pa-gripper and gripper-silicone.  With
    ``output_edge`` the spring and the port act on the layout's "output_edge" (the spring
    ``k/2`` times the edge's mean of ``u_y²``, Δ the edge's mean of ``-u_y``), which takes zero
    pressure as the rest of the right edge does."""
    se_max, objective_ref = mechanism_scales(p, width, height, 3.0)
    out = "output_edge" if output_edge else "output"
    zero = ("zero_pressure", "fixed") + (("output_edge",) if output_edge else ())
    return Setup(supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                 springs=(Spring(out, p.k_out, (0.0, 1.0)),),
                 port=Port(out, (0.0, -1.0)), solid=("block", "jaw_pad"),
                 void=("jaw_void",), objective="mechanism",
                 pressure=Pressure(inlet=("inlet",), zero=zero),
                 se_max=se_max, objective_ref=objective_ref)
