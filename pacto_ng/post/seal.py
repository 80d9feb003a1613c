"""Is each pressure chamber of a thresholded design sealed?  (SPEC §8, "Sealed".)

The part is the solid {ρ ≥ t} of the nodal field ρ: the element densities ρ̄ averaged to the
vertices (area- or volume-weighted over the *included* elements only, the passive void materials
``exclude`` left out, as :mod:`.threshold` and :mod:`.part3d` do; a vertex within 1e-9 of t
counts as solid), clipped by pyvista's ``clip_scalar``.  A vertex is *void* when ρ < t - 1e-9
or when it belongs to no included element (inside a passive void region).  The void regions
are the connected components (``scipy.sparse.csgraph``) of a graph on the vertices and the
excluded elements:

* **Simplices.** On a triangle or tetrahedron the clip is {ρ < t} of the linear interpolant,
  the element cut by a half-space: convex, so its void vertices lie in one void piece, and
  every void piece holds a vertex (a linear function is least at a vertex).  All void vertices
  of an included simplex are joined.
* **Quadrilaterals and hexahedra.** Void vertices joined by an element edge are joined (ρ is
  linear along it).  Void vertices that are not (diagonal corners) would meet in the
  multilinear field if its saddle value is < t, but the part is what ``clip_scalar`` builds,
  and its case tables resolve every such ambiguity in favour of the kept (solid) side: for all
  16 quadrilateral and 256 hexahedron sign patterns the clip's void pieces are exactly the
  void vertices joined by void edges (checked in tests/post/test_seal.py).  ``multilinear=
  "clip"`` (default) joins along edges only; ``"mean"`` also joins all void vertices of an
  element whose mean nodal value is < t (the mean standing for the saddle value: leaks that
  the built part does not have).
* **Passive void.** Each excluded element is a void node, joined to its void vertices and to
  the excluded elements it shares a facet with (an edge in 2D, a face in 3D).
* **Inlet and zero.** A boundary facet named in ``inlet`` seeds through its void vertices and
  the excluded elements it borders; a facet named in ``zero`` is reached the same way.  A
  chamber is a component holding a seed; it *leaks* if it holds a zero node too.  Other
  boundaries (symmetry, fixed, free) are walls, never leaks.

A chamber is named by the passive void materials in it, else by its inlet boundaries (numbered
when several share them).  A leak's opening is the reached zero point (a void vertex on a zero
facet, or the centroid of a zero facet of an excluded element) nearest in straight-line distance
to the chamber's seed points, and its boundary that point's.  With no seed at all (the inlet
covered by solid, no passive void behind it) there is no chamber: sealed.  Two materials: pass
ρ̄1 (the solid, either material); nothing else changes.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .runs import design_density

_TIE = 1e-9  # nodal values this close to the threshold count as solid
_FACETS = {(2, 3): ((0, 1), (1, 2), (2, 0)), (2, 4): ((0, 1), (1, 2), (2, 3), (3, 0)),
           (3, 4): ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)),
           (3, 8): ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                    (3, 0, 4, 7))}
_EDGES = {(2, 4): _FACETS[(2, 4)], (3, 8): ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6),
                                            (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))}
_HEX_TETS = ((0, 6, 1, 2), (0, 6, 2, 3), (0, 6, 3, 7), (0, 6, 7, 4), (0, 6, 4, 5), (0, 6, 5, 1))
_WIDTH = {2: 2, 3: 4}  # vertices of the widest facet


@dataclass(frozen=True)
class Chamber:
    """A chamber: its ``name``, whether it is ``sealed``, and for a leak the zero-pressure
    ``boundary`` reached and a point of the ``opening`` (module docstring); None if sealed."""

    name: str
    sealed: bool
    boundary: str | None = None
    opening: tuple | None = None


@dataclass(frozen=True)
class Seal:
    """The result of :func:`check_seal`: the ``threshold`` and the ``chambers`` (by name)."""

    threshold: float
    chambers: tuple

    @property
    def sealed(self) -> bool:
        """Every chamber sealed (True without chambers)."""
        return all(c.sealed for c in self.chambers)

    @property
    def leaking(self) -> tuple:
        """The chambers that leak."""
        return tuple(c for c in self.chambers if not c.sealed)

    def to_json(self) -> dict:
        """A JSON-ready dict: ``sealed``, ``threshold`` and per chamber ``name``, ``sealed``,
        ``boundary`` and ``opening`` (``[x, y(, z)]``; None when sealed)."""
        return {"sealed": self.sealed, "threshold": float(self.threshold),
                "chambers": [{"name": c.name, "sealed": c.sealed, "boundary": c.boundary,
                              "opening": None if c.opening is None else list(c.opening)}
                             for c in self.chambers]}

    def message(self) -> str:
        """One sentence for the user."""
        t = f"{self.threshold:g}"
        if not self.chambers:
            return (f"sealed: no void touches the inlet at threshold {t} (the inlet is covered "
                    "by solid), so there is no chamber to leak")
        if self.sealed:
            names = ", ".join(c.name for c in self.chambers)
            return (f"sealed: every chamber ({names}) is closed off from the zero-pressure "
                    f"boundaries by solid at threshold {t}")
        leak = self.leaking
        at = [f"the zero-pressure boundary '{c.boundary}' near ("
              + ", ".join(f"{v:.4g}" for v in c.opening) + ") m" for c in leak]
        head = (f"chamber '{leak[0].name}' is open to the outside: its void reaches {at[0]}"
                if len(leak) == 1 else "chambers {} are open to the outside: {}".format(
                    ", ".join(f"'{c.name}'" for c in leak),
                    "; ".join(f"'{c.name}' reaches {w}" for c, w in zip(leak, at))))
        return (f"{head} at threshold {t}; the part will not hold pressure (raise the volume "
                "fraction, or limit the leak: --set leak_max=...)")


def _vertex_table(nodes, sizes, what, width=None):
    """Netgen's 1-based, 0-padded node table as 0-based vertex ids, -1-padded (to ``width``
    columns if given, else to the most vertices), and the vertex counts."""
    nodes = np.asarray(nodes, dtype=np.int64) - 1
    counts = np.count_nonzero(nodes >= 0, axis=1)
    bad = ~np.isin(counts, sizes)
    if bad.any():
        raise ValueError(f"{what}s with {sorted(set(counts[bad].tolist()))} vertices are not "
                         f"supported (only {sizes})")
    width = width or max(int(counts.max(initial=0)), 1)
    out = np.full((len(nodes), width), -1, dtype=np.int64)
    out[:, :min(width, nodes.shape[1])] = nodes[:, :width]
    return out, counts


def _boundary_facets(mesh):
    """``(facets, names)``: the boundary elements' vertex ids (sorted, -1-padded to the facet
    width) and boundary names."""
    ngm, dim = mesh.ngmesh, mesh.dim
    els = (ngm.Elements1D() if dim == 2 else ngm.Elements2D()).NumPy()
    sizes = (2,) if dim == 2 else (3, 4)
    f, _ = _vertex_table(els["nodes"], sizes, "boundary element", _WIDTH[dim])
    names = np.array(mesh.GetBoundaries(), dtype=object)[np.asarray(els["index"]) - 1]
    return np.sort(f, axis=1), names


def _measures(pts, cells, counts, dim):
    """Area (2D) or volume (3D) of every element (a hexahedron as six tetrahedra)."""
    w = np.zeros(len(cells))
    for k in np.unique(counts):
        rows = counts == k
        p = pts[cells[rows, :k]]
        if dim == 2:  # the diagonals' cross product: exact for any simple quadrilateral
            a, b = (p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]) if k == 4 else \
                (p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
            w[rows] = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        else:
            for i, j, m, n in ((0, 1, 2, 3),) if k == 4 else _HEX_TETS:
                a, b, c = (p[:, q] - p[:, i] for q in (j, m, n))
                w[rows] += np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0
    return w


def _element_links(V, void, value, t, dim, multilinear="clip"):
    """Graph edges ``(a, b)`` joining the void vertices of the included elements ``V`` (one
    kind: ``(m, k)`` vertex ids) by the rules of the module docstring; ``value``: the
    tie-broken nodal field."""
    k = V.shape[1]
    vv = void[V]
    rows, cols = [], []
    if k == dim + 1:
        whole = np.ones(len(V), dtype=bool)
    else:
        for a, b in _EDGES[(dim, k)]:
            m = vv[:, a] & vv[:, b]
            rows.append(V[m, a])
            cols.append(V[m, b])
        whole = value[V].mean(axis=1) < t if multilinear == "mean" else np.zeros(len(V), bool)
    sel = whole & vv.any(axis=1)
    Vs, vs = V[sel], vv[sel]
    first = Vs[np.arange(len(Vs)), np.argmax(vs, axis=1)]
    for j in range(k):
        rows.append(first[vs[:, j]])
        cols.append(Vs[vs[:, j], j])
    return np.concatenate(rows), np.concatenate(cols)


def _facet_keys(cells, counts, idx, dim):
    """Sorted, -1-padded vertex ids of the facets of the elements ``idx``, and their owners."""
    keys, owner = [np.zeros((0, _WIDTH[dim]), dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for k in np.unique(counts[idx]):
        own = idx[counts[idx] == k]
        for f in _FACETS[(dim, k)]:
            key = np.full((len(own), _WIDTH[dim]), -1, dtype=np.int64)
            key[:, :len(f)] = cells[own][:, f]
            keys.append(key)
            owner.append(own)
    return np.sort(np.concatenate(keys), axis=1), np.concatenate(owner)


def _passive_links(cells, counts, excl, bfacets, dim):
    """The excluded elements' facet neighbours ``(i, j)`` (local numbers) and the boundary
    facets' excluded elements ``(facet, i)``."""
    keys, owner = _facet_keys(cells, counts, excl, dim)
    local = np.full(len(cells), -1)
    local[excl] = np.arange(len(excl))
    allk = np.concatenate([keys, bfacets])
    gid = np.unique(allk, axis=0, return_inverse=True)[1].ravel()
    ng = int(gid.max(initial=-1)) + 1
    E = coo_matrix((np.ones(len(keys)), (gid[:len(keys)], local[owner])),
                   shape=(ng, len(excl))).tocsr()
    B = coo_matrix((np.ones(len(bfacets)), (np.arange(len(bfacets)), gid[len(keys):])),
                   shape=(len(bfacets), ng)).tocsr()
    return (E.T @ E).tocoo(), (B @ E).tocoo()


def _points(sel, bfacets, bnames, vpad, fx, pts, nv):
    """Graph nodes, coordinates and boundary names of the void vertices on the facets ``sel``
    and of the excluded elements behind them (at the facet's centroid)."""
    F = bfacets[sel]
    m = (F >= 0) & vpad[F]
    which = np.isin(fx.row, np.flatnonzero(sel))
    G = bfacets[fx.row[which]]
    cen = (pts[G] * (G >= 0)[..., None]).sum(axis=1) / (G >= 0).sum(axis=1)[:, None]
    return (np.r_[F[m], nv + fx.col[which]], np.r_[pts[F[m]].reshape(-1, pts.shape[1]), cen],
            np.r_[np.broadcast_to(bnames[sel][:, None], F.shape)[m], bnames[fx.row[which]]])


def _checked_names(mesh, inlet, zero):
    inlet, zero = ((n,) if isinstance(n, str) else tuple(n) for n in (inlet, zero))
    unknown = sorted((set(inlet) | set(zero)) - set(mesh.GetBoundaries()))
    if unknown:
        raise ValueError(f"unknown boundary name(s) {', '.join(unknown)}; the mesh has "
                         f"{', '.join(sorted(set(mesh.GetBoundaries())))}")
    both = sorted(set(inlet) & set(zero))
    if both:
        raise ValueError(f"boundary {', '.join(both)} is both inlet and zero-pressure")
    return inlet, zero


def check_seal(mesh, rho, threshold, *, inlet, zero, exclude=(), multilinear="clip") -> Seal:
    """Which chambers of the part {ρ ≥ threshold} of ``rho`` are sealed (module docstring).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        2D (triangles, quadrilaterals) or 3D (tetrahedra, hexahedra), first order.
    rho : array_like, shape (mesh.ne,)
        Element densities ρ̄ in NGSolve element order (two materials: ρ̄1).
    threshold : float
        In (0, 1).
    inlet, zero : str or iterable of str
        The pressure inlet and the zero-pressure boundaries.
    exclude : iterable of str
        Passive void materials (unknown names are ignored).
    multilinear : {"clip", "mean"}
        How a quadrilateral or hexahedron joins diagonal void vertices (module docstring).

    Returns
    -------
    Seal

    Raises
    ------
    ValueError
        Unknown ``inlet``/``zero`` names, a name in both, ``threshold`` outside (0, 1), ``rho``
        of the wrong length, every element excluded, or unsupported elements.
    """
    inlet, zero = _checked_names(mesh, inlet, zero)
    t = float(threshold)
    if not 0.0 < t < 1.0:
        raise ValueError(f"threshold must lie in (0, 1), got {threshold!r}")
    if multilinear not in ("clip", "mean"):
        raise ValueError(f"multilinear must be 'clip' or 'mean', not {multilinear!r}")
    pts, cells, counts, mats = _tables(mesh)
    rho = np.asarray(rho, dtype=float).ravel()
    if rho.size != len(cells):
        raise ValueError(f"rho has {rho.size} values but the mesh has {len(cells)} elements")
    exclude = (exclude,) if isinstance(exclude, str) else tuple(exclude)
    inc = ~np.isin(mats, list(exclude))
    if not inc.any():
        raise ValueError(f"every element of the mesh is in an excluded material "
                         f"({', '.join(sorted(exclude))})")
    nodal = _included_nodal(pts, cells, counts, rho, inc)
    value = np.where(np.abs(nodal - t) <= _TIE, t + _TIE, nodal)
    void = value < t
    vpad = np.append(void, False)  # -1 (padding) reads False
    excl = np.flatnonzero(~inc)
    bfacets, bnames = _boundary_facets(mesh)
    labels, fx = _components(cells, counts, inc, void, value, t, bfacets, pts.shape[1],
                             multilinear)
    nv = len(pts)
    seeds = _points(np.isin(bnames, inlet), bfacets, bnames, vpad, fx, pts, nv)
    zeros = _points(np.isin(bnames, zero), bfacets, bnames, vpad, fx, pts, nv)
    return Seal(t, _chambers(labels, seeds, zeros, mats[excl], nv))


def _tables(mesh):
    """``(points, cells, counts, materials)`` of the volume elements of ``mesh``."""
    dim, ngm = mesh.dim, mesh.ngmesh
    els = (ngm.Elements2D() if dim == 2 else ngm.Elements3D()).NumPy()
    cells, counts = _vertex_table(els["nodes"], (3, 4) if dim == 2 else (4, 8), "element")
    mats = np.array(mesh.GetMaterials(), dtype=object)[np.asarray(els["index"]) - 1]
    return np.asarray(ngm.Coordinates(), dtype=float)[:, :dim], cells, counts, mats


def _included_nodal(pts, cells, counts, rho, inc):
    """The area- (3D: volume-) weighted mean of ``rho`` over the included elements ``inc``
    around every vertex; -inf at a vertex of no included element."""
    dim = pts.shape[1]
    w = _measures(pts, cells, counts, dim)[inc]
    c = cells[inc]
    own = np.broadcast_to(np.arange(len(c))[:, None], c.shape)[c >= 0]
    den = np.bincount(c[c >= 0], weights=w[own], minlength=len(pts))
    num = np.bincount(c[c >= 0], weights=(w * rho[inc])[own], minlength=len(pts))
    return np.where(den > 0, num / np.where(den > 0, den, 1.0), -np.inf)


def _components(cells, counts, inc, void, value, t, bfacets, dim, multilinear):
    """The void regions: a component label for every vertex, then every excluded element
    (node ``nv + i`` for the i-th), and the boundary facets' excluded elements."""
    nv = len(void)
    links = [_element_links(cells[inc & (counts == k), :k], void, value, t, dim, multilinear)
             for k in np.unique(counts[inc])]
    rows, cols = [a for a, _ in links], [b for _, b in links]
    excl = np.flatnonzero(~inc)
    xx, fx = _passive_links(cells, counts, excl, bfacets, dim)
    E = cells[excl]
    m = (E >= 0) & np.append(void, False)[E]
    rows += [np.broadcast_to(nv + np.arange(len(excl))[:, None], E.shape)[m], nv + xx.row]
    cols += [E[m], nv + xx.col]
    n = nv + len(excl)
    r, q = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r)), (r, q)), shape=(n, n)).tocsr()
    return connected_components(graph, directed=False)[1], fx


def _chambers(labels, seeds, zeros, excl_mats, nv):
    """The chambers (sorted by name) of the components ``labels`` holding a seed."""
    found = []
    for lab in np.unique(labels[seeds[0]]):
        mine, hit = labels[seeds[0]] == lab, labels[zeros[0]] == lab
        name = ", ".join(sorted(set(excl_mats[labels[nv:] == lab]))
                         or sorted(set(seeds[2][mine])))
        if not hit.any():
            found.append((name, True, None, None))
            continue
        k = int(np.argmin(cKDTree(seeds[1][mine]).query(zeros[1][hit])[0]))
        found.append((name, False, str(zeros[2][hit][k]), tuple(map(float, zeros[1][hit][k]))))
    found.sort(key=lambda f: f[0])
    names = [f[0] for f in found]
    return tuple(Chamber(f"{n} #{names[:i + 1].count(n)}" if names.count(n) > 1 else n, *rest)
                 for i, (n, *rest) in enumerate(found))


def inlet_names(problem, setup) -> tuple[str, ...]:
    """The pressure inlets of a run: ``--set inlet`` if given, else the set-up's (none without
    a pressure load)."""
    if setup.pressure is None:
        return ()
    if problem.params.inlet:
        return tuple(problem.params.inlet.split("|"))
    return tuple(setup.pressure.inlet)


def design_seal(problem, setup, threshold: float, exclude=()) -> Seal | None:
    """The seal of the part {ρ ≥ ``threshold``} of the design ``problem`` holds (its final
    ρ̄; two materials ρ̄1), ``exclude`` the passive void materials; None without a pressure
    load."""
    if setup.pressure is None:
        return None
    return check_seal(problem.mesh, design_density(problem), threshold,
                      inlet=inlet_names(problem, setup), zero=setup.pressure.zero,
                      exclude=exclude)


def warn_if_open(seal: Seal | None) -> None:
    """A chamber open to the outside: one warning line on stderr (even with ``--quiet``)."""
    if seal is not None and not seal.sealed:
        print(f"pacto: warning: NOT SEALED: {seal.message()}", file=sys.stderr, flush=True)

