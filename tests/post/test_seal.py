"""Is each chamber of a thresholded design sealed? (pacto_ng.post.seal)

Exact figures used below (structured meshes, densities 0/1 aligned with the elements, the
nodal field the area-weighted mean of the elements around a vertex): a vertex between void
and solid elements on a straight interface gets 1/2, which counts as solid at t = 0.5 (the tie
rule), so a void channel of the structured mesh is open only at the vertices strictly inside
it; a vertex with all its elements at ρ̄ gets ρ̄.
"""
import itertools

import numpy as np
import pytest

from pacto_ng.box import Block, Box, Patch, netgen_box_mesh, structured_box
from pacto_ng.mesh import Layout, Region, Segment, netgen_mesh, structured_mesh
from pacto_ng.post.seal import Seal, check_seal

# --- 2D: a 0.1 x 0.05 rectangle, outer edges ``zero``, a passive void chamber (wall ``inlet``)
W, H = 0.1, 0.05
CH = (0.03, 0.015, 0.07, 0.03)  # the chamber x0, y0, x1, y1
h2 = 0.002  # element size of the 2D meshes
MOUTH = (0.046, 0.054)  # x-range of the channel from the chamber's top wall to the top edge


def _zero_edges(w, h, name="zero"):
    return tuple(Segment(name, a, b) for a, b in (((0, 0), (w, 0)), ((w, 0), (w, h)),
                                                   ((w, h), (0, h)), ((0, h), (0, 0))))


def _layout(*chambers):
    return Layout(W, H, segments=_zero_edges(W, H),
                  regions=tuple(Region(n, "void", *box, boundary="inlet") for n, box in chambers))


def _mesh2d(kind, layout):
    return structured_mesh(layout, 50, 25) if kind == "quad" else netgen_mesh(layout, h2)


def _centroids(mesh):
    ngm = mesh.ngmesh
    els = (ngm.Elements2D() if mesh.dim == 2 else ngm.Elements3D()).NumPy()
    nodes = np.asarray(els["nodes"], dtype=int) - 1
    pts = np.asarray(ngm.Coordinates())[:, :mesh.dim]
    used = nodes >= 0
    return (pts[nodes] * used[..., None]).sum(axis=1) / used.sum(axis=1)[:, None]


def _in_box(c, lo, hi):
    return np.all((c > np.asarray(lo)) & (c < np.asarray(hi)), axis=1)


def _design(mesh, lo, hi, value=0.0):
    """ρ̄ = 1 except ``value`` in the box ``lo``-``hi`` (by the element centroid)."""
    return np.where(_in_box(_centroids(mesh), lo, hi), value, 1.0)


def _seal(mesh, rho, t=0.5, **kw):
    return check_seal(mesh, rho, t, inlet="inlet", zero="zero", exclude=("chamber",), **kw)


@pytest.fixture(scope="module", params=["quad", "trig"])
def chamber2d(request):
    return request.param, _mesh2d(request.param, _layout(("chamber", CH)))


def test_2d_all_solid_is_sealed(chamber2d):
    _, mesh = chamber2d
    seal = _seal(mesh, np.ones(mesh.ne))
    assert seal.sealed
    assert seal.chambers == (seal.chambers[0],) and seal.chambers[0].name == "chamber"
    assert seal.chambers[0].boundary is None and seal.chambers[0].opening is None
    assert "every chamber (chamber)" in seal.message()


def test_2d_channel_to_the_top_leaks_at_its_mouth(chamber2d):
    """A channel 4 quads (8 mm) wide from the chamber's top wall to the top edge: the zero
    vertices it reaches lie on the top edge inside the mouth x in (0.046, 0.054)."""
    _, mesh = chamber2d
    seal = _seal(mesh, _design(mesh, (MOUTH[0], CH[3] - 1e-3), (MOUTH[1], H + 1)))
    assert not seal.sealed
    (leak,) = seal.leaking
    assert (leak.name, leak.boundary) == ("chamber", "zero")
    x, y = leak.opening
    assert abs(y - H) < 1e-12
    assert MOUTH[0] - h2 <= x <= MOUTH[1] + h2
    js = seal.to_json()
    assert js["sealed"] is False and js["threshold"] == 0.5
    assert js["chambers"] == [{"name": "chamber", "sealed": False, "boundary": "zero",
                               "opening": [x, y]}]
    msg = seal.message()
    assert "chamber 'chamber' is open" in msg and "'zero'" in msg and "leak_max" in msg


def test_2d_channel_one_element_short_is_sealed():
    """The channel stops at y = H - h: the vertices of its end get 1/2 (solid at 0.5), the top
    row of elements is solid, so no top-edge vertex is void."""
    mesh = _mesh2d("quad", _layout(("chamber", CH)))
    seal = _seal(mesh, _design(mesh, (MOUTH[0], CH[3] - 1e-3), (MOUTH[1], H - h2)))
    assert seal.sealed and [c.name for c in seal.chambers] == ["chamber"]


def test_2d_one_element_channel_is_closed_by_the_tie_rule():
    """A channel one quad wide: every vertex of it touches two void and two solid elements
    (1/2), solid at t = 0.5 and at t = 0.5 + 5e-10 (within 1e-9: the tie rule), so the part is
    solid there; void at t = 0.51."""
    mesh = _mesh2d("quad", _layout(("chamber", CH)))
    rho = _design(mesh, (0.048, CH[3] - 1e-3), (0.050, H + 1))
    assert _seal(mesh, rho, 0.5).sealed and _seal(mesh, rho, 0.5 + 5e-10).sealed
    (leak,) = _seal(mesh, rho, 0.51).leaking
    assert leak.boundary == "zero" and 0.048 - 1e-12 <= leak.opening[0] <= 0.050 + 1e-12


def test_2d_passive_void_slot_one_element_wide_leaks_through_its_facets():
    """A passive void slot one quad wide ([48, 50] x [30, 50] mm) from the chamber to the top
    edge, everything else solid: its vertices all touch solid design elements (nodal 1, solid),
    so only the slot's elements sharing edges carry the void to the top edge; the opening is
    the centroid (0.049, 0.05) of the slot's zero edge."""
    lay = Layout(W, H, segments=_zero_edges(W, H),
                 regions=(Region("chamber", "void", *CH, boundary="inlet"),
                          Region("slot", "void", 0.048, CH[3], 0.050, H)))
    mesh = structured_mesh(lay, 50, 25)
    seal = check_seal(mesh, np.ones(mesh.ne), 0.5, inlet="inlet", zero="zero",
                      exclude=("chamber", "slot"))
    (leak,) = seal.leaking
    assert (leak.name, leak.boundary) == ("chamber, slot", "zero")
    np.testing.assert_allclose(leak.opening, (0.049, H), atol=1e-12)


def test_2d_threshold_moves_the_verdict():
    """A channel of ρ̄ = 0.4: its inner vertices are 0.4 (void at t = 0.5, solid at t = 0.3),
    its side vertices (0.4 + 1)/2 = 0.7."""
    mesh = _mesh2d("quad", _layout(("chamber", CH)))
    rho = _design(mesh, (MOUTH[0], CH[3] - 1e-3), (MOUTH[1], H + 1), 0.4)
    assert _seal(mesh, rho, 0.5).leaking[0].boundary == "zero"
    low = _seal(mesh, rho, 0.3)
    assert low.sealed and low.chambers[0].name == "chamber"


def test_2d_two_chambers_one_open():
    lay = _layout(("left", (0.01, 0.015, 0.04, 0.03)), ("right", (0.06, 0.015, 0.09, 0.03)))
    mesh = _mesh2d("quad", lay)
    seal = check_seal(mesh, _design(mesh, (0.07, 0.029), (0.08, 1.0)), 0.5, inlet="inlet",
                      zero="zero", exclude=("left", "right"))
    assert not seal.sealed
    assert [(c.name, c.sealed) for c in seal.chambers] == [("left", True), ("right", False)]
    assert seal.leaking[0].boundary == "zero" and 0.07 <= seal.leaking[0].opening[0] <= 0.08
    assert "chamber 'right' is open" in seal.message()


def test_diagonal_chain_touching_at_vertices():
    """10 x 10 quads of 1 mm, void elements (i, i) from the inlet's corner (0, 0) to the zero
    edge's corner (L, L), the rest solid.  Neighbouring chain elements share one vertex of
    value 1/2 (two void, two solid elements); the other two corners of a chain element are 3/4
    (one void, three solid), so a chain element has void corners on one diagonal only, of mean
    (1/2 + 1/2 + 3/4 + 3/4)/4 = 0.625.  t = 0.5: the shared vertices are solid (tie rule):
    sealed under both rules.  t = 0.7: they are void, the 3/4 corners solid: the mean rule
    joins each chain element's diagonal (0.625 < 0.7), open; the clip rule does not, sealed.
    t = 0.8: every chain element is void at all corners: open under both."""
    L = 0.01
    lay = Layout(L, L, segments=(Segment("inlet", (0, L), (0, 0)), Segment("zero", (L, 0), (L, L))))
    mesh = structured_mesh(lay, 10, 10)
    c = _centroids(mesh)
    rho = np.where(np.abs(c[:, 0] - c[:, 1]) < 1e-6, 0.0, 1.0)
    kw = dict(inlet="inlet", zero="zero")
    for rule in ("clip", "mean"):
        seal = check_seal(mesh, rho, 0.5, multilinear=rule, **kw)
        assert seal.sealed and [ch.name for ch in seal.chambers] == ["inlet"]
        (leak,) = check_seal(mesh, rho, 0.8, multilinear=rule, **kw).leaking
        assert leak.boundary == "zero"
        assert np.hypot(*(np.array(leak.opening) - (L, L))) <= 1e-3 + 1e-12
    (leak,) = check_seal(mesh, rho, 0.7, multilinear="mean", **kw).leaking
    assert leak.boundary == "zero"
    assert np.hypot(*(np.array(leak.opening) - (L, L))) <= 1e-3 + 1e-12
    assert check_seal(mesh, rho, 0.7, **kw).sealed


def _two_by_two():
    """2 x 2 unit quads with ρ̄ = 0.4 (lower left), 0.62, 0.62, 0 (upper right): nodal values
    (0,0) 0.4, (1,0) = (0,1) = 0.51, (1,1) = 1.64/4 = 0.41, (2,1) = (1,2) = 0.31, (2,2) = 0.
    The lower-left quad has void corners (0,0), (1,1) on one diagonal and solid ones 0.51 on
    the other, mean 1.83/4 = 0.4575 (bilinear saddle value 0.0961/0.21 = 0.4576)."""
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(quads=True, nx=2, ny=2)
    c = _centroids(mesh)
    rho = np.select([(c[:, 0] < 0.5) & (c[:, 1] < 0.5), (c[:, 0] > 0.5) & (c[:, 1] > 0.5)],
                    [0.4, 0.0], 0.62)
    return mesh, rho


def test_mean_rule_and_clip_rule_on_a_diagonal_quad():
    """Inlet: the left edge (void only at (0,0)); zero: the top edge.  The mean rule joins the
    diagonal at t = 0.5 (0.4575 < 0.5): open, at (0.5, 1) (the reached top vertex nearest to
    (0,0)); not at t = 0.45.  The clip rule never joins it: sealed at both."""
    mesh, rho = _two_by_two()
    kw = dict(inlet="left", zero="top")
    mean = check_seal(mesh, rho, 0.5, multilinear="mean", **kw)
    assert mean.leaking[0].boundary == "top"
    np.testing.assert_allclose(mean.leaking[0].opening, (0.5, 1.0), atol=1e-12)
    assert check_seal(mesh, rho, 0.45, multilinear="mean", **kw).sealed
    assert check_seal(mesh, rho, 0.5, **kw).sealed
    assert check_seal(mesh, rho, 0.45, **kw).sealed


def test_clip_rule_is_what_pyvista_builds_on_the_two_by_two():
    """The part's own clip (grid.nodal_density, pyvista clip_scalar, as threshold.py does)
    keeps (0,0) and the top-edge vertex (0.5, 1) in different void pieces at t = 0.5."""
    from pacto_ng.post.grid import mesh_to_pyvista, nodal_density

    mesh, rho = _two_by_two()
    grid = mesh_to_pyvista(mesh)
    grid.point_data["rho"] = nodal_density(mesh, rho)
    void = grid.clip_scalar(scalars="rho", value=0.5, invert=True).connectivity("all")
    pts = np.asarray(void.points)[:, :2]
    region = np.asarray(void.point_data["RegionId"])
    at = [region[np.argmin(np.hypot(*(pts - p).T))] for p in ((0, 0), (0.5, 1.0))]
    assert at[0] != at[1]


def _clip_groups(kind, void):
    """Pyvista's clip_scalar of one unit quad/hexahedron (VTK/Netgen vertex order) with
    values 0.2 (void) / 0.8 (solid): the void piece of each void vertex."""
    import pyvista as pv

    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1],
                    [0, 1, 1]], dtype=float)[:len(void)]
    grid = pv.UnstructuredGrid(np.r_[len(void), np.arange(len(void))], np.array([kind], np.uint8),
                               pts)
    grid.point_data["r"] = np.where(void, 0.2, 0.8) + np.linspace(0.0, 0.05, len(void))
    cut = grid.clip_scalar(scalars="r", value=0.5, invert=True).connectivity("all")
    region = np.asarray(cut.point_data["RegionId"])
    return {int(i): region[np.argmin(np.linalg.norm(cut.points - pts[i], axis=1))]
            for i in np.flatnonzero(void)}


def test_clip_rule_matches_pyvista_clip_for_every_sign_pattern():
    """All 2^4 quadrilateral and 2^8 hexahedron void patterns: two void vertices share a void
    piece of pyvista's clip exactly when the clip rule joins them."""
    import pyvista as pv
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from pacto_ng.post.seal import _element_links

    for n, dim, kind in ((4, 2, pv.CellType.QUAD), (8, 3, pv.CellType.HEXAHEDRON)):
        for bits in itertools.product((False, True), repeat=n):
            void = np.array(bits)
            if void.all() or not void.any():
                continue
            a, b = _element_links(np.arange(n)[None, :], void, np.where(void, 0.2, 0.8), 0.5,
                                  dim)
            lab = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)),
                                       directed=False)[1]
            piece = _clip_groups(kind, void)
            for i, j in itertools.combinations(piece, 2):
                assert (piece[i] == piece[j]) == (lab[i] == lab[j]), (bits, i, j)


def _clipped_void_verdict(mesh, rho, t):
    """The oracle: the void of the part as pyvista clips it (the nodal field of grid.py,
    tie-broken as threshold.py and part3d.py do; ``clip_scalar(invert=True)``), its pieces by
    pyvista's connectivity; sealed when no piece holds a vertex of both ``inlet`` and ``zero``."""
    from scipy.spatial import cKDTree

    from pacto_ng.post.grid import area_weighted_nodal, cell_areas, cell_volumes, mesh_to_pyvista
    from pacto_ng.post.seal import _boundary_facets

    grid = mesh_to_pyvista(mesh)
    nod = area_weighted_nodal(grid, rho, (cell_areas if mesh.dim == 2 else cell_volumes)(grid))
    grid.point_data["rho"] = np.where(np.abs(nod - t) <= 1e-9, t + 1e-9, nod)
    void = grid.clip_scalar(scalars="rho", value=t, invert=True)
    if void.n_cells == 0:
        return True
    void = void.connectivity("all")
    region = np.asarray(void.point_data["RegionId"])
    dist, idx = cKDTree(np.asarray(void.points)).query(np.asarray(grid.points))
    facets, names = _boundary_facets(mesh)

    def pieces(name):
        v = np.unique(facets[names == name])
        v = v[v >= 0]
        return set(region[idx[v[dist[v] < 1e-12]]])
    return not pieces("inlet") & pieces("zero")


def _oracle_mesh(kind):
    from small_cases import small_pa_layout

    box = Box(1, 1, 1, patches=(Patch("inlet", "xmin"), Patch("zero", "xmax"),
                                Patch("zero", "zmax")))
    return {"quad": lambda: structured_mesh(small_pa_layout(), 40, 20),
            "trig": lambda: netgen_mesh(small_pa_layout(), 0.0006),
            "hex": lambda: structured_box(box, 12, 12, 12),
            "tet": lambda: netgen_box_mesh(box, 0.1)}[kind]()


@pytest.mark.parametrize("kind", ["quad", "trig", "hex", "tet"])
def test_verdict_is_that_of_the_clipped_part(kind):
    """Smooth designs (products of sines) at thresholds 0.3 ... 0.7: check_seal says sealed
    exactly when pyvista's clipped void joins no inlet vertex to a zero vertex (both verdicts
    occur)."""
    mesh = _oracle_mesh(kind)
    c = _centroids(mesh) / np.ptp(np.asarray(mesh.ngmesh.Coordinates()), axis=0)
    rng = np.random.default_rng(3)
    verdicts = []
    for _ in range(3):
        k, phase = rng.uniform(1, 4, size=3), rng.uniform(0, 6, size=3)
        rho = 0.5 + 0.5 * np.prod(np.sin(np.pi * k[:mesh.dim] * c + phase[:mesh.dim]), axis=1)
        for t in (0.3, 0.4, 0.5, 0.6, 0.7):
            seal = check_seal(mesh, rho, t, inlet="inlet", zero="zero")
            assert seal.sealed == _clipped_void_verdict(mesh, rho, t), (t, seal.message())
            verdicts.append(seal.sealed)
    assert any(verdicts) and not all(verdicts)


def test_nodal_field_is_the_one_the_part_is_clipped_from():
    """With a passive void chamber: 2D against threshold.py's nodal field, 3D against part3d's
    (included_grid, volume-weighted), at the vertices of included elements."""
    from pacto_ng.post.grid import area_weighted_nodal, cell_volumes
    from pacto_ng.post.part3d import included_grid
    from pacto_ng.post.seal import _included_nodal, _tables
    from pacto_ng.post.threshold import threshold

    rng = np.random.default_rng(0)
    mesh = netgen_mesh(_layout(("chamber", CH)), 0.004)
    pts, cells, counts, mats = _tables(mesh)
    rho = rng.uniform(size=mesh.ne)
    mine = _included_nodal(pts, cells, counts, rho, mats != "chamber")
    ref = threshold(mesh, rho, 0.5, exclude=("chamber",)).nodal
    use = np.isfinite(mine) & (np.abs(ref - 0.5) > 1e-8)
    assert use.sum() > 0.9 * mesh.nv
    np.testing.assert_allclose(mine[use], ref[use], rtol=1e-12)
    mesh = netgen_box_mesh(_box(), 0.008)
    pts, cells, counts, mats = _tables(mesh)
    rho = rng.uniform(size=mesh.ne)
    mine = _included_nodal(pts, cells, counts, rho, mats != "chamber")
    grid, keep = included_grid(mesh, ("chamber",))
    ref = area_weighted_nodal(grid, rho[keep], cell_volumes(grid))
    ids = np.asarray(grid.point_data["vtkOriginalPointIds"])
    np.testing.assert_allclose(mine[ids], ref, rtol=1e-12)
    assert np.all(np.isinf(np.delete(mine, ids)))  # inside the chamber: void


def test_a_hundred_thousand_hexahedra_take_well_under_a_second():
    import time

    mesh = structured_box(Box(1, 1, 1, patches=(Patch("inlet", "xmin"), Patch("zero", "xmax"))),
                          47, 47, 47)
    rho = np.random.default_rng(1).uniform(size=mesh.ne)
    took = []
    for _ in range(2):
        start = time.perf_counter()
        seal = check_seal(mesh, rho, 0.5, inlet="inlet", zero="zero")
        took.append(time.perf_counter() - start)
    assert mesh.ne > 1e5 and not seal.sealed  # white noise: void everywhere connects
    assert min(took) < 1.0


# --- an inlet on the outer boundary (the small pa-inverter's layout) -------------------------
def test_outer_inlet_void_on_the_symmetry_line_is_sealed():
    """20 x 10 quads of 1 mm; inlet: the left edge, zero: the top (but the fixed part) and the
    right edge, symmetry: the bottom.  A void block [0, 8] x [0, 4] mm touches the inlet and the
    symmetry line only."""
    from small_cases import small_pa_mesh

    mesh = small_pa_mesh("quad")
    seal = check_seal(mesh, _design(mesh, (-1, -1), (0.008, 0.004)), 0.5, inlet="inlet",
                      zero="zero")
    assert seal.sealed and [c.name for c in seal.chambers] == ["inlet"]


def test_outer_inlet_void_reaching_the_right_edge_leaks():
    from small_cases import PA_L, small_pa_mesh

    mesh = small_pa_mesh("quad")
    seal = check_seal(mesh, _design(mesh, (-1, -1), (1, 0.004)), 0.5, inlet="inlet",
                      zero="zero")
    (leak,) = seal.leaking
    assert (leak.name, leak.boundary) == ("inlet", "zero")
    assert abs(leak.opening[0] - PA_L) < 1e-12 and 0.0 <= leak.opening[1] < 0.004


def test_no_seed_is_sealed_without_chambers():
    from small_cases import small_pa_mesh

    mesh = small_pa_mesh("quad")
    seal = check_seal(mesh, np.ones(mesh.ne), 0.5, inlet="inlet", zero="zero")
    assert isinstance(seal, Seal) and seal.sealed and seal.chambers == ()
    assert seal.to_json() == {"sealed": True, "threshold": 0.5, "chambers": []}
    assert "no chamber" in seal.message()


def test_unknown_boundary_names_raise():
    from small_cases import small_pa_mesh

    mesh = small_pa_mesh("quad")
    with pytest.raises(ValueError, match="outlet.*skin|skin.*outlet"):
        check_seal(mesh, np.ones(mesh.ne), 0.5, inlet="outlet", zero=("zero", "skin"))


# --- 3D: a 40 mm cube, faces ``zero``, a passive void chamber [10, 30]^3 mm (faces ``inlet``)
B, h3 = 0.04, 0.005
TUNNEL = ((0.012, 0.012, 0.029), (0.028, 0.028, 1.0))  # from the chamber's top to z = B


def _box():
    return Box(B, B, B, patches=tuple(Patch("zero", s) for s in
                                      ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")),
               blocks=(Block("chamber", "void", (0.01,) * 3, (0.03,) * 3, boundary="inlet"),))


@pytest.fixture(scope="module", params=["tet", "hex"])
def chamber3d(request):
    return netgen_box_mesh(_box(), 0.005) if request.param == "tet" else \
        structured_box(_box(), 8, 8, 8)


def test_3d_all_solid_is_sealed(chamber3d):
    seal = _seal(chamber3d, np.ones(chamber3d.ne))
    assert seal.sealed and [c.name for c in seal.chambers] == ["chamber"]


def test_3d_tunnel_to_the_top_leaks_at_its_mouth(chamber3d):
    """A 16 mm square tunnel from the chamber to the top face: the opening lies on the top face
    within one element of the tunnel's mouth."""
    seal = _seal(chamber3d, _design(chamber3d, *TUNNEL))
    (leak,) = seal.leaking
    assert (leak.name, leak.boundary) == ("chamber", "zero")
    x, y, z = leak.opening
    assert abs(z - B) < 1e-9
    lo, hi = TUNNEL[0][0] - h3, TUNNEL[1][0] + h3
    assert lo <= x <= hi and lo <= y <= hi
