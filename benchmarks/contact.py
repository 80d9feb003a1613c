"""What self-contact costs in a part's analysis: Newton iterations and seconds per pressure.

    python3 -m benchmarks contact [--out docs/studies.md]

A block 1 x 1 m with a slot 0.02 m high open at its right end (from x = 0.3), clamped on its
left side, E = 1 MPa, ν = 0.3, is pressed on its top and bottom faces: the slot's walls meet
at about 1 kPa (plane strain in 2D; in 3D the block is 0.2 m deep).  Each row solves the
pressures given in turn, each from the last equilibrium, as ``pacto analyse --contact`` does
(:class:`pacto_ng.post.part_analysis.PartAnalysis`: penalty self-contact, Newton with the
pairs fixed, then paired anew until they hold), and reports the last pressure's Newton
iterations (over all its pairings) and seconds, and the seconds of the same solves without
contact.  The candidate walls are the slot's, or every wall of the part as a run's part
stage takes them.  "sliding" loads the top face only: the block bends and the slot's upper
wall slides along the lower one.
"""
from __future__ import annotations

import time

#: (label, dimension, model, order, Netgen maxh, candidate walls, pressures in Pa, faces pressed)
ROWS = (
    ("2D slot", 2, "neohookean", 2, 0.05, "slot", (100.0, 3e3), "both"),
    ("2D slot", 2, "linear", 2, 0.05, "slot", (3e3,), "both"),
    ("2D sliding", 2, "neohookean", 2, 0.05, "slot", (3e3, 1e4), "top"),
    ("3D slot", 3, "linear", 1, 0.2, "slot", (3e3,), "both"),
    ("3D slot", 3, "linear", 2, 0.2, "slot", (3e3,), "both"),
    ("3D slab", 3, "linear", 2, 0.1, "every wall", (1e3, 3e3), "both"),
)


def slotted(dim: int, maxh: float, pressed: str):
    """The slotted block (2D) or slab (3D): ``fixed`` at x = 0, ``pressure`` on the faces
    pressed, ``slot`` the slot's walls, ``free`` the rest."""
    from netgen.occ import Box, MoveTo, OCCGeometry, X, Y
    from ngsolve import Mesh

    if dim == 2:
        body = (MoveTo(0, 0).Rectangle(1, 1).Face()
                - MoveTo(0.3, 0.49).Rectangle(0.8, 0.02).Face())
        walls = body.edges
    else:
        body = Box((0, 0, 0), (1, 1, 0.2)) - Box((0.3, 0.49, -0.1), (1.1, 0.51, 0.3))
        walls = body.faces
    walls.name = "free"
    walls.Min(X).name = "fixed"
    walls.Max(Y).name = "pressure"
    if pressed == "both":
        walls.Min(Y).name = "pressure"
    for wall in walls:
        if 0.48 < wall.center.y < 0.52 and wall.center.x > 0.29:
            wall.name = "slot"
    geo = OCCGeometry(body, dim=2) if dim == 2 else OCCGeometry(body)
    return Mesh(geo.GenerateMesh(maxh=maxh))


def one(row) -> dict:
    """One row of :data:`ROWS` solved with and without contact."""
    from pacto_ng import Parameters, Port
    from pacto_ng.physics.mechanics import Supports
    from pacto_ng.physics.walls import solid_boundaries
    from pacto_ng.post.part_analysis import PartAnalysis

    label, dim, model, order, maxh, walls, pressures, pressed = row
    mesh = slotted(dim, maxh, pressed)
    params = Parameters(model=model, E1=1e6, E0=1.0, nu=0.3, plane="strain", thickness=1.0,
                        order=order)
    contact = ("slot",) if walls == "slot" else solid_boundaries(mesh)
    out = {"row": row, "elements": mesh.ne}
    for key, names in (("without", ()), ("with", contact)):
        ana = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("fixed",)),
                           ports=Port("pressure", (0.0, -1.0, 0.0)[:dim]), contact=names)
        for P in pressures:
            start = time.perf_counter()
            point = ana.solve(P)
            out[key] = (point.converged, point.iterations, time.perf_counter() - start)
    return out


def report(results) -> str:
    lines = ["| part | model | order | elements | candidate walls | pressures (Pa) | converged | "
             "Newton iterations at the last | s at the last | s without contact | ratio |",
             "|---|---|---|---:|---|---|---|---:|---:|---:|---:|"]
    for r in results:
        label, _, model, order, _, walls, pressures, _ = r["row"]
        ok, its, s = r["with"]
        s0 = r["without"][2]
        lines.append(f"| {label} | {model} | {order} | {r['elements']} | {walls} | "
                     f"{', '.join(f'{P:g}' for P in pressures)} | {'yes' if ok else 'no'} | "
                     f"{its} | {s:.2f} | {s0:.3f} | {s / s0:.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    from benchmarks.__main__ import standalone

    standalone(argv, "contact", "Self-contact in a part's analysis: Newton iterations and seconds", __doc__, ROWS, one, report)


if __name__ == "__main__":
    main()
