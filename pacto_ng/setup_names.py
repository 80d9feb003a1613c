"""The names a case's set-up refers to, checked against its mesh: every region, boundary and
point exists with the right kind (:func:`check_setup_names`), directions and forces have one
component per dimension (:func:`check_vectors`), a passive void lies inside the design body
(:func:`check_void_inside_design`) and a pressure inlet borders the design
(:func:`check_inlet_touches_design`); each failure is one InputError naming the role, the name
and the names that exist.
"""
from __future__ import annotations

import numpy as np

from .errors import InputError


def _names(values) -> str:
    shown = sorted({v for v in values if v})
    return ", ".join(shown) if shown else "none"


def check_setup_names(mesh, setup, *, extra_boundaries=()) -> None:
    """Every name a case's set-up refers to exists in the mesh, with the right kind; else an
    InputError naming the role, the name and the names that exist."""
    regions = set(mesh.GetMaterials())
    boundaries = set(mesh.GetBoundaries())
    points = set(mesh.GetBBoundaries()) - {""}  # 2D: vertices; 3D: edges
    if mesh.dim == 3:
        points |= set(mesh.GetBBBoundaries()) - {""}  # and vertices

    def need(kind, role, name):
        have = {"region": regions, "boundary": boundaries,
                "boundary or point": boundaries | points}[kind]
        if name not in have:
            listing = (f"regions: {_names(regions)}" if kind == "region" else
                       f"boundaries: {_names(boundaries)}; points: {_names(points)}")
            raise InputError(f"setup: {role} '{name}' is not a {kind} of the geometry ({listing})")

    if "design" not in regions:
        kind = "solid" if mesh.dim == 3 else "face"
        raise InputError(f"geometry: no {kind} is named 'design' (regions: {_names(regions)}); "
                         f"name the design domain, e.g. {kind}.name = 'design'")
    for name in setup.solid:
        need("region", "passive solid", name)
    for name in setup.void:
        need("region", "passive void", name)
    both = set(setup.solid) & set(setup.void)
    if both:
        raise InputError(f"setup: region '{sorted(both)[0]}' is both passive solid and passive "
                         "void")
    if "design" in set(setup.solid) | set(setup.void):
        raise InputError("setup: 'design' is the design domain; it cannot be passive")
    if setup.void:
        check_void_inside_design(mesh, setup.void)
    sup = setup.supports
    if sup.fix_z and mesh.dim < 3:
        raise InputError(f"setup: fix_z support on a {mesh.dim}D geometry")
    for role, names in (("clamp", sup.clamp), ("fix_x support", sup.fix_x),
                        ("fix_y support", sup.fix_y), ("fix_z support", sup.fix_z)):
        for name in names:
            need("boundary or point", role, name)
    for ld in setup.loads:
        need("boundary or point", "load", ld.region)
    for sp in setup.springs:
        need("boundary or point", "spring", sp.region)
    for port in setup.ports:
        need("boundary or point", "output port", port.region)
    if setup.pressure is not None:
        for name in setup.pressure.inlet:
            need("boundary", "pressure inlet", name)
        for name in setup.pressure.zero:
            if name not in extra_boundaries:
                need("boundary", "zero-pressure boundary", name)


def check_vectors(mesh, setup) -> None:
    """Directions and forces carry one component per space dimension, and are not zero."""
    d = mesh.dim
    for role, items, attr in (("output port", setup.ports, "direction"),
                              ("spring", setup.springs, "direction"),
                              ("load", setup.loads, "force")):
        for it in items:
            vec = np.asarray(getattr(it, attr), dtype=float)
            if vec.shape != (d,):
                raise InputError(f"setup: {role} '{it.region}': {attr} {tuple(vec)} has "
                                 f"{vec.size} components, the mesh is {d}D")
            if attr == "direction" and not np.linalg.norm(vec) > 0:
                raise InputError(f"setup: {role} '{it.region}': direction is zero")


def _region_neighbours(mesh) -> dict[str, set[str]]:
    """The regions each region shares a facet with (an edge in 2D, a face in 3D): a vertex
    alone does not join two regions."""
    from ngsolve import VOL

    owner, neighbours = {}, {name: set() for name in mesh.GetMaterials()}
    for el in mesh.Elements(VOL):
        for f in el.facets:
            other = owner.setdefault(f.nr, el.mat)
            if other != el.mat:
                neighbours[other].add(el.mat)
                neighbours[el.mat].add(other)
    return neighbours


def check_void_inside_design(mesh, passive_void: tuple[str, ...]) -> None:
    """Every passive void region (a chamber) lies inside the design body: it shares a facet
    with the design domain, or with a passive region joined to it by facets.  A chamber face
    glued beside the body instead of cut out of it, or a void region that does not touch the
    design, is a separate body of void: its displacement is held by nothing and the
    analysis' linear solve fails.  One InputError naming the region."""
    neighbours = _region_neighbours(mesh)
    body, todo = {"design"}, ["design"]
    while todo:  # the regions joined to the design domain by facets
        for other in neighbours.get(todo.pop(), ()):
            if other not in body:
                body.add(other)
                todo.append(other)
    kind, facet = ("solid", "face") if mesh.dim == 3 else ("face", "edge")
    for name in passive_void:
        if name in body:
            continue
        others = neighbours.get(name, set()) - {name}
        borders = (f"; it borders only {kind} {_names(others)}, which the design does not "
                   "border either" if others else "")
        raise InputError(f"void: {kind} '{name}' does not lie inside the design body (it shares "
                         f"no {facet} with {kind} 'design'{borders}): cut the chamber out of the "
                         "body and glue it back (see docs/tutorial.md)")


def check_inlet_touches_design(mesh, inlet: tuple[str, ...], passive_void: tuple[str, ...]):
    """A pressure inlet must border the design domain (or a passive void region, a chamber,
    that does): an inlet on passive solid, or one that meets the design at a vertex only,
    pressurises nothing.  "Border": a facet of the inlet (an edge in 2D, a face in 3D) is a
    facet of an element of the design domain or of a passive void region."""
    from ngsolve import VOL

    wet = {"design", *passive_void}
    for name in inlet:
        facets = set()
        for el in mesh.Boundaries(name).Elements():
            facets.update(f.nr for f in (el.faces if mesh.dim == 3 else el.edges))
        bordering = {el.mat for el in mesh.Elements(VOL)
                     if any(f.nr in facets for f in el.facets)}
        if not bordering & wet:
            where = ("a face of the 'design' solid" if mesh.dim == 3 else
                     "an edge of the 'design' face")
            raise InputError(f"setup: pressure inlet '{name}' touches no design domain (it "
                             f"borders {_names(bordering)}); put it on {where} or of a chamber "
                             "inside it")
