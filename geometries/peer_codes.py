"""The domains of Kumar's published MATLAB codes, node for node (unit square elements).

Both codes fix their Dirichlet values node by node; here each such node set is the set of mesh
nodes on a few named boundary segments and points.  The Darcy block gives p = 0 wherever an
inlet node also lies on a zero-pressure boundary, so a corner node that the code puts at P_in
is kept off every zero-pressure segment: the first element edge next to it is a segment of
its own that carries no pressure condition (its other node gets its value from the next
segment).

``sorotop(nelx, nely)`` — SoRoTop.m's pressure-actuated mechanism (half domain, symmetry at
the bottom edge y = 0): "inlet" the whole left edge (both its corners at P_in, the code's
order of assignment); "zero_pressure" the top edge from x = 1 and the whole right edge;
"clamp_corner" the top edge's first element edge (clamped, no pressure condition) and
"clamp" the rest of the code's clamped top nodes x = 0 .. k-1 with k = floor(nely/20) (the
code counts its clamped nodes with nely, not nelx; k = 1: point "clamp_point" and a free
"top_corner" edge); "symmetry" the bottom edge; point
"output" the bottom-right corner; passive solid "block" over the top floor(nely/20) rows and
the left floor(nelx/20) columns of elements.

``topress(nelx, nely)`` — TOPress.m's pressure-loaded structure: "inlet" the whole bottom
edge (both its corners at P_in); "zero_pressure" the left and right edges from y = 1 and the
whole top edge; "foot_left", "foot_right" the first element edge of each side edge (no
pressure condition); points "support_left", "support_right" the bottom corners (clamped).
"""
from pacto_ng import InputError
from pacto_ng.mesh import Layout, Region, Segment


def clamped_nodes(nely: int) -> int:
    """SoRoTop's clamped top nodes: ``Tnode(1:nely/20)``, the first floor(nely/20); below
    nely = 20 the code clamps none (a singular stiffness): one here (coarse checks only)."""
    return max(1, nely // 20)


def sorotop_names(nely: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The names :func:`sorotop` clamps and those (beyond "zero_pressure") at p = 0."""
    k = clamped_nodes(nely)
    if k == 1:
        return ("clamp_point",), ()
    return ("clamp_corner",) + (("clamp",) if k > 2 else ()), (("clamp",) if k > 2 else ())


def sorotop(nelx: int, nely: int) -> Layout:
    L, H = float(nelx), float(nely)
    if nelx < 2 or nely < 2:
        raise InputError("sorotop: nelx and nely must be at least 2")
    k = clamped_nodes(nely)
    # the top edge's first element edge: clamped (k >= 2) or free, never at p = 0, so that
    # the corner node keeps the inlet's P_in
    top = [Segment("clamp_corner" if k > 1 else "top_corner", (0.0, H), (1.0, H))]
    if k > 2:
        top.append(Segment("clamp", (1.0, H), (k - 1.0, H)))
    top.append(Segment("zero_pressure", (max(1.0, k - 1.0), H), (L, H)))
    segments = (Segment("inlet", (0.0, H), (0.0, 0.0)), *top,
                Segment("zero_pressure", (L, 0.0), (L, H)),
                Segment("symmetry", (0.0, 0.0), (L, 0.0)))
    # passive block: floor(nely/20) rows x floor(nelx/20) columns (at least one each here)
    block = Region("block", "solid", 0.0, H - k, float(max(1, nelx // 20)), H)
    points = (("output", (L, 0.0)),) + ((("clamp_point", (0.0, H)),) if k == 1 else ())
    return Layout(L, H, segments=segments, regions=(block,), points=points)


def topress(nelx: int, nely: int) -> Layout:
    L, H = float(nelx), float(nely)
    if nelx < 2 or nely < 2:
        raise InputError("topress: nelx and nely must be at least 2")
    segments = (Segment("inlet", (0.0, 0.0), (L, 0.0)),
                Segment("foot_right", (L, 0.0), (L, 1.0)),
                Segment("zero_pressure", (L, 1.0), (L, H)),
                Segment("zero_pressure", (L, H), (0.0, H)),
                Segment("zero_pressure", (0.0, H), (0.0, 1.0)),
                Segment("foot_left", (0.0, 1.0), (0.0, 0.0)))
    return Layout(L, H, segments=segments,
                  points=(("support_left", (0.0, 0.0)), ("support_right", (L, 0.0))))
