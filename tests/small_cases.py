"""Small shared set-ups of the tests."""
import ngsolve as ng
import numpy as np
from netgen import occ

from pacto_ng.mesh import Layout, Region, Segment, netgen_mesh, structured_mesh

#: a small pa-inverter (Δs = 0.002 is resolved by the meshes of :func:`small_pa_mesh`)
PA_L, PA_H = 0.02, 0.01


def small_pa_layout() -> Layout:
    L, H = PA_L, PA_H
    return Layout(L, H, segments=(Segment("inlet", (0, H), (0, 0)),
                                  Segment("fixed", (0, H), (L / 10, H)),
                                  Segment("zero", (L / 10, H), (L, H)),
                                  Segment("zero", (L, 0), (L, H)),
                                  Segment("symmetry", (0, 0), (L, 0))),
                  regions=(Region("block", "solid", 0, 0.9 * H, L / 10, H),),
                  points=(("output", (L, 0)),))


def small_pa_mesh(kind: str):
    """``"netgen"``/``"trig"``: Netgen triangles of size 1.2 mm; otherwise 20 x 10 quads."""
    if kind in ("netgen", "trig"):
        return netgen_mesh(small_pa_layout(), 0.0012)
    return structured_mesh(small_pa_layout(), 20, 10)


def chain_fd(chain, name, x0, **options):
    """:func:`~pacto_ng.core.check_gradient` of the chain's value ``name`` against its adjoint
    gradient at ``x0`` (``options``: h, directions, stencil)."""
    from pacto_ng.core import check_gradient

    def fun(x):
        return float(chain.forward(x=x)[name])

    def grad(x):
        chain.forward(x=x)
        return chain.gradient(name)

    return check_gradient(fun, grad, x0, **options)


def pa_chain(mesh, dar, mech):
    """The small pa-inverter's chain around a Darcy block ``dar`` and a mechanics block ``mech``
    on ``mesh``: x -> Embed -> Helmholtz filter (2 mm) -> projection (β = 2) -> FixPassive ->
    Darcy -> mechanics -> output displacement at "output" (inward), strain energy, -Δ/SE;
    returns ``(chain, x0)`` with a random design ``x0`` in [0.2, 0.8]."""
    import numpy as np

    from pacto_ng.core import Chain
    from pacto_ng.design import DesignField, Embed, FixPassive
    from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
    from pacto_ng.physics.loads import Port
    from pacto_ng.responses import MechanismRatio, StrainEnergy, output_displacement

    field = DesignField(mesh, solid=("block",))
    chain = Chain([Embed(field), HelmholtzFilter(mesh, 0.002), HeavisideProjection(2.0),
                   FixPassive(field), dar, mech,
                   output_displacement(mech, Port("output", (-1.0, 0.0))), StrainEnergy(mech),
                   MechanismRatio(scale=1.0)])
    return chain, np.random.default_rng(1).uniform(0.2, 0.8, field.n)


def run_with_design(out, argv, design):
    """``pacto run`` of ``argv`` (one short run) into ``out``, then its checkpoint's design
    replaced by ``design(centroids)`` of the design elements: a run folder whose final design a
    test chose (for the post-analysis tests)."""
    from pacto_ng.cli import main
    from pacto_ng.post.runs import load_run, rebuild

    assert main(["run", *argv, "--out", str(out), "--quiet"]) == 0
    problem = rebuild(load_run(out, "test"))
    x = design(problem.field.centroids()[problem.field.design_index]).astype(float)
    ck = out / "checkpoint.npz"
    with np.load(ck) as data:
        saved = {k: data[k] for k in data.files}
    saved["x"] = x
    np.savez(ck, **saved)
    return out


def unit_square(maxh: float, points: dict):
    """The unit square meshed at ``maxh``: edges bottom, top, left, right; its corners named
    by ``points`` ({name: (x, y)})."""
    shape = occ.MoveTo(0, 0).Rectangle(1.0, 1.0).Face()
    for e in shape.edges:
        c = e.center
        e.name = ("bottom" if c.y < 1e-9 else "top" if c.y > 1 - 1e-9 else
                  "left" if c.x < 1e-9 else "right")
    for name, (px, py) in points.items():
        shape.vertices.Nearest((px, py, 0)).name = name
    return ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
