"""A body-fitted Netgen mesh of a thresholded design, with its boundaries named by location.

The geometry of the part is traced from the thresholded polygons (:mod:`.traced`), or, given
the netgen.occ shape the source mesh was made from (``domain``), built on that shape's own edges
where the solid reaches them (:mod:`.domain_part`); should the latter fail, the traced geometry
is used.  Netgen meshes it with triangles of size ``maxh``; the material is ``solid``.

Names carried over from the source mesh:

* boundary segments on the source's outer boundary keep that boundary's name (``fixed``,
  ``symmetry``, ``inlet``, ...); the other boundary segments are ``free``;
* **the wetting rule** — a boundary segment of the new mesh is renamed ``pressure`` when

  - it lies on a source boundary whose name is in ``wet_boundaries`` (the fluid is on the
    other side of the domain boundary, e.g. the inlet), or
  - it lies inside the source domain and the pressure field at its midpoint moved a distance
    ``probe`` (default: the source element size) along the outward normal of the solid — its
    cavity side — is at least ``wet_fraction`` (default 0.5) times the inlet pressure
    ``p_in`` (default: the largest nodal pressure).  A probe point outside the source mesh
    sees zero pressure.

* every named point (co-dimension 2 region) of the source becomes the nearest vertex of the
  new mesh.

Solid pieces that touch none of the ``clamp`` boundaries would float (a singular stiffness):
they are dropped and reported; if no piece touches the clamp, :func:`remesh` raises.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .boundary import BoundaryLocator, named_points, outer_boundary, point_sets
from .domain_part import domain_shape
from .materials import INTERFACE, assign_elementwise, split_part
from .sampler import pressure_sampler
from .threshold import Thresholded
from .traced import build_geometry

PRESSURE = "pressure"


def _mesher_errors() -> tuple:
    """The exceptions OCC and Netgen raise on a shape they cannot build or mesh: Netgen's
    ``NgException`` (e.g. "OCC-Triangulation could not be built for face 1", "error in wire
    builder"), netgen.occ's ``OCCException``, and OCC's ``Standard_Failure``, which the bindings
    raise as a RuntimeError (e.g. "Standard_ConstructionError: Bnd_Box is void" for an empty
    shape)."""
    from netgen.libngpy._meshing import NgException
    from netgen.occ import OCCException

    return NgException, OCCException, RuntimeError


@dataclass
class Remeshed:
    """The result of :func:`remesh`.

    Attributes
    ----------
    mesh : ngsolve.Mesh
        Triangle mesh of the solid (material ``solid``) with the named boundaries and points.
    area : float
        Area of the new mesh.
    thresholded_area : float
        Area of the clipped solid it was built from (:attr:`Thresholded.area`).
    dropped_area : float
        Area of the floating pieces that were dropped.
    ports : dict
        Point name -> ``(source position, new vertex position)``.
    wetted_length : float
        Length of the ``pressure`` boundary.
    p_in : float or None
        The inlet pressure the wetting rule used.
    geometry : str
        ``"traced"`` (the part's whole boundary traced from the thresholded polygons) or
        ``"domain"`` (on the domain's own edges where the solid reaches them); ``"traced
        (...)"`` says why a given domain was not used.
    """

    mesh: object
    area: float
    thresholded_area: float
    dropped_area: float = 0.0
    ports: dict = field(default_factory=dict)
    wetted_length: float = 0.0
    p_in: float | None = None
    geometry: str = "traced"
    materials: str | None = None


def _unmeshed_edges(ngm) -> int:
    """The boundary segments of a Netgen mesh that border no triangle (an empty face)."""
    edges = set()
    for el in ngm.Elements2D():
        vs = [v.nr for v in el.vertices]
        edges.update((min(a, b), max(a, b)) for a, b in zip(vs, vs[1:] + vs[:1]))
    ends = ([v.nr for v in s.vertices][:2] for s in ngm.Elements1D())
    return sum((min(a, b), max(a, b)) not in edges for a, b in ends)


def _generate(shape, maxh: float, threshold: float):
    """The Netgen mesh of ``shape`` at ``maxh``; ValueError (one line) when Netgen fails: an
    OCC triangulation error, or a face left without triangles ("NOT ALL FACES HAVE BEEN
    MESHED").  (Retrying at 0.7 and 0.5 maxh was tried on two such PneuNet parts and did not
    help, so there is no retry.)"""
    from netgen import occ

    try:
        ngm = occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh)
    except _mesher_errors() as err:
        what = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    else:
        bad = _unmeshed_edges(ngm)
        if not bad:
            return ngm
        what = f"{bad} boundary edges have no triangle (a face of the traced geometry was left empty)"
    raise ValueError(f"Netgen could not mesh the part: {what}; threshold {threshold:g}, maxh "
                     f"{maxh:g}: try another threshold or maxh")


def _generate_part(part, maxh: float, threshold: float, stiff, domain, source):
    """``(ngm, materials)``: the Netgen mesh of the part's shape; with a stiff region (two
    materials) cut into ``soft`` and ``stiff`` faces, or, should that fail, the one-material
    mesh with its elements assigned by ρ̄2 (see :mod:`.materials`)."""
    if stiff is None:
        return _generate(part, maxh, threshold), None
    try:
        return _generate(split_part(part, stiff, domain), maxh, threshold), "body-fitted"
    except (ValueError, *_mesher_errors()) as err:  # _generate's, split_part's: element by element
        what = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    ngm = _generate(part, maxh, threshold)
    assign_elementwise(ngm, stiff, source)
    return ngm, f"element-wise (the interface as a boundary failed: {what})"


# ---------------------------------------------------------------------------------------
def remesh(th: Thresholded, maxh: float, *, clamp=("fixed",), pressure=None,
           p_in: float | None = None, wet_fraction: float = 0.5, wet_boundaries=("inlet",),
           probe: float | None = None, min_spacing: float | None = None,
           spline_tol: float | None = None, domain=None, stiff=None) -> Remeshed:
    """Mesh the thresholded solid with Netgen triangles and carry the names over.

    Parameters
    ----------
    th : Thresholded
        Output of :func:`~pacto_ng.post.threshold.threshold`.
    maxh : float
        Element size of the new mesh.
    clamp : sequence of str
        Boundary names of the source that support the structure.  Pieces touching none of them
        are dropped; empty: keep every piece.
    pressure : CoefficientFunction, GridFunction, ndarray or callable, optional
        The pressure field on the source mesh (see :func:`~.sampler.pressure_sampler`); None: only
        the ``wet_boundaries`` are wetted.
    p_in : float, optional
        Inlet pressure of the wetting rule; default the largest nodal pressure.
    wet_fraction : float
        A segment inside the domain is wetted where ``p(probe point) >= wet_fraction * p_in``.
    wet_boundaries : sequence of str
        Source boundaries whose solid parts are wetted (the fluid lies beyond them).
    probe : float, optional
        Distance of the probe point from the segment midpoint, default the source element size.
    min_spacing, spline_tol : float, optional
        Geometry parameters of :func:`~.traced.build_geometry`.
    domain : netgen.occ shape, optional
        The geometry the source mesh was made from (a face, or a glued compound of named
        faces).  Given, the part is built by :func:`~.domain_part.build_domain_geometry`:
        wherever the solid reaches the domain's boundary (a curved outline, a hole, the wall of
        a void face) the part's boundary is that edge of the domain, with its name; the faces
        named in ``th.excluded`` (the ``exclude`` of :func:`~.threshold.threshold`: passive
        void faces) are not part of the domain.  Should that geometry fail (an OCC error, or
        Netgen cannot mesh it) the traced geometry is used and :attr:`Remeshed.geometry` says
        why.
    stiff : :class:`~.materials.StiffRegion`, optional
        Two materials: the part is cut into ``soft`` and ``stiff`` faces along an
        ``interface`` (:func:`~.materials.split_part`); should that fail, the one-material part
        is meshed and its elements are assigned by ρ̄2 (:func:`~.materials.assign_elementwise`).
        The ``interface`` edges are never wetted.

    Returns
    -------
    Remeshed

    Raises
    ------
    ValueError
        If no solid touches the clamp boundary, or ``maxh`` is not positive.
    """
    import ngsolve

    if maxh <= 0:
        raise ValueError("maxh must be positive")
    if not 0.0 < wet_fraction <= 1.0:
        raise ValueError(f"wet_fraction must lie in (0, 1], got {wet_fraction!r}")
    kept, dropped = _clamped_pieces(th, clamp)
    src = th.source
    seg, names = outer_boundary(src)
    diam = float(np.ptp(seg.reshape(-1, 2), axis=0).max())
    locator = BoundaryLocator(seg, names, 1e-8 * max(diam, th.h))
    ngm, geometry, materials = _part_mesh(th, kept, maxh, locator, domain, stiff,
                                          min_spacing, spline_tol)
    coords = np.asarray(ngm.Coordinates(), dtype=float)
    sample = pressure_sampler(pressure, src) if pressure is not None else None
    if sample is not None and p_in is None:
        p_in = float(np.max(sample(np.asarray(src.ngmesh.Coordinates(), dtype=float))))
    probe = th.h if probe is None else float(probe)
    wetted = _wet(ngm, coords, src, locator, geometry == "domain", sample, p_in, probe,
                  wet_fraction, wet_boundaries)
    ports = _named_points(ngm, coords, src)
    mesh = ngsolve.Mesh(ngm)
    area = ngsolve.Integrate(ngsolve.CF(1.0), mesh)
    return Remeshed(mesh, float(area), th.area, float(dropped), ports, wetted, p_in,
                    geometry, materials)


def _clamped_pieces(th: Thresholded, clamp) -> tuple[list, float]:
    """``(kept, dropped area)``: the solid pieces that touch a ``clamp`` boundary or hold a
    clamped named point (every piece when ``clamp`` is empty), and the area of the others,
    which would float."""
    clamp = (clamp,) if isinstance(clamp, str) else tuple(clamp)
    comps = list(th.components)
    if not comps:
        raise ValueError("the thresholded design has no solid")
    if clamp:
        # a clamped point (a pin support) holds the piece it lies in
        points = [q for name, qs in point_sets(th.source).items() if name in clamp for q in qs]
        tol = 1e-6 * th.h
        kept = [c for c in comps if c.names & set(clamp) or any(c.holds(q, tol) for q in points)]
        if not kept:
            raise ValueError(f"no solid touches the clamp {'|'.join(clamp)} "
                             f"(threshold {th.threshold:g})")
    else:
        kept = comps
    return kept, sum(c.area for c in comps if c not in kept)


def _part_mesh(th: Thresholded, kept, maxh, locator, domain, stiff, min_spacing, spline_tol):
    """``(ngm, geometry, materials)``: the Netgen mesh of the kept pieces, on the domain's own
    geometry when ``domain`` is given and that works, else on the traced one
    (:attr:`Remeshed.geometry` says which, and why)."""
    src = th.source
    if domain is not None:
        try:
            part = domain_shape(th, kept, domain, min_spacing, spline_tol)
            ngm, materials = _generate_part(part, maxh, th.threshold, stiff, domain, src)
            return ngm, "domain", materials
        except (ValueError, *_mesher_errors()) as err:  # the traced part instead
            what = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            geometry = f"traced (the part on the domain's geometry failed: {what})"
    else:
        geometry = "traced"
    shape = build_geometry(kept, th.h, min_spacing=min_spacing, spline_tol=spline_tol,
                           locator=locator)
    ngm, materials = _generate_part(shape, maxh, th.threshold, stiff, None, src)
    return ngm, geometry, materials


def _segments(ngm, coords):
    """The boundary segments of ``ngm``: ``(segs, mid, length, normal)``, their midpoints,
    lengths and unit normals pointing out of the solid."""
    centroid = {}
    for el in ngm.Elements2D():
        vs = [v.nr - 1 for v in el.vertices]
        c = coords[vs].mean(axis=0)
        for a, b in zip(vs, vs[1:] + vs[:1]):
            centroid[(min(a, b), max(a, b))] = c
    segs = list(ngm.Elements1D())
    ends = np.array([[v.nr - 1 for v in s.vertices][:2] for s in segs])
    mid = 0.5 * (coords[ends[:, 0]] + coords[ends[:, 1]])
    tang = coords[ends[:, 1]] - coords[ends[:, 0]]
    length = np.linalg.norm(tang, axis=1)
    normal = np.c_[tang[:, 1], -tang[:, 0]] / length[:, None]
    inner = np.array([centroid[(min(a, b), max(a, b))] for a, b in ends])
    flip = np.einsum("ij,ij->i", normal, inner - mid) > 0
    normal[flip] *= -1.0  # outward from the solid
    return segs, mid, length, normal


def _wet(ngm, coords, src, locator, on_domain: bool, sample, p_in, probe, wet_fraction,
         wet_boundaries) -> float:
    """The wetting rule (module docstring), segment by segment: the wetted segments of ``ngm``
    are renamed ``pressure``; returns their length."""
    segs, mid, length, normal = _segments(ngm, coords)
    current = [ngm.GetBCName(s.index - 1) for s in segs]
    internal = np.array([c == INTERFACE for c in current])
    if on_domain:
        # names are the domain's: wetted by name wherever the part runs along a wetted edge
        # (an outer inlet, or a chamber's wall); everywhere else by the pressure beyond it (a
        # probe point outside the source mesh sees none)
        wet = np.array([c in wet_boundaries for c in current])
        if sample is not None and p_in is not None and p_in > 0:
            q = mid + probe * normal
            inside = np.asarray(src(q[:, 0].copy(), q[:, 1].copy())["nr"]) >= 0
            pv = np.where(inside, sample(q), 0.0)
            wet |= pv >= wet_fraction * p_in
    else:
        on_outer = np.array([n is not None for n in locator.locate(mid)])
        wet = np.array([c in wet_boundaries for c in current]) & on_outer
        if sample is not None and p_in is not None and p_in > 0:
            pv = sample(mid + probe * normal)
            wet |= (~on_outer) & (pv >= wet_fraction * p_in)
    wet &= ~internal  # the interface between two materials lies inside the part
    if wet.any():
        idx = ngm.AddRegion(PRESSURE, dim=1)
        for s, w in zip(segs, wet):
            if w:
                s.index = idx
    return float(length[wet].sum())


def _named_points(ngm, coords, src) -> dict:
    """Every named point of the source as the nearest vertex of ``ngm`` (added as a point
    element unless the part already has it): ``{name: (source position, vertex position)}``."""
    import ngsolve
    from netgen.meshing import Element0D

    # (a part on the domain's geometry already has the domain's named vertices it kept: a
    # second point element of the same name would count a port's spring and reading twice)
    ports, have = {}, named_points(ngsolve.Mesh(ngm))
    for name, (px, py) in named_points(src).items():
        k = int(np.argmin(np.hypot(coords[:, 0] - px, coords[:, 1] - py)))
        if name not in have:
            idx = ngm.AddRegion(name, dim=0)
            ngm.Add(Element0D(k + 1, index=idx))
        else:
            k = int(np.argmin(np.hypot(coords[:, 0] - have[name][0],
                                       coords[:, 1] - have[name][1])))
        ports[name] = ((px, py), tuple(coords[k]))
    return ports
