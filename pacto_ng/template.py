"""``pacto new NAME``: a commented case file that runs as written."""
from __future__ import annotations

from pathlib import Path

from .errors import InputError
from .files import atomic_write_text

TEMPLATE = '''"""{name}: a soft finger with a round chamber that bends down under pressure.

A case file for pacto_ng.  Run it with

    pacto run {file}                  # optimise (output/{name}-linear/)
    pacto run {file} --show-parameters
    pacto check-gradients {file}      # finite-difference check of the whole chain
    pacto analyse output/{name}-linear   # threshold, remesh, Neo-Hookean re-analysis

Edit the geometry, the set-up and the defaults below; every name used comes from the public
API (``import pacto_ng as pn``) and netgen.occ.
"""
from netgen import occ

import pacto_ng as pn

LENGTH, HEIGHT = 0.08, 0.02      # finger length and height (m)
CHAMBER_R = 0.005                # radius of the round chamber (m)


def geometry(p: pn.Parameters):
    """A netgen.occ shape with named faces and edges (the names the set-up refers to)."""
    L, H = LENGTH, HEIGHT
    # the outline: straight bottom, a round tip, straight top, the clamped left edge
    body = (occ.WorkPlane().MoveTo(0, 0).LineTo(L - H / 2, 0, name="outer")
            .Arc(H / 2, 180, name="outer").LineTo(0, H, name="outer")
            .LineTo(0, 0, name="fixed").Face())
    chamber = occ.WorkPlane().Circle(0.35 * L, 0.5 * H, CHAMBER_R).Face()
    chamber.edges.name = "inlet"          # the pressure enters through the chamber's wall
    chamber.faces.name = "chamber"        # a passive void region
    design = body - chamber
    design.faces.name = "design"          # the design domain is always called "design"
    shape = occ.Glue([design, chamber])
    # a point port: the vertex where the bottom edge meets the round tip
    shape.vertices.Nearest((L - H / 2, 0, 0)).name = "tip"
    return shape


def setup(p: pn.Parameters) -> pn.Setup:
    """Supports, pressure, the output port and the objective, by the geometry's names."""
    return pn.Setup(
        supports=pn.Supports(clamp=("fixed",)),
        # Δ = -u_y at the tip (it bends down), against an output spring of k_out N/m
        port=pn.Port("tip", (0.0, -1.0), spring=p.k_out),
        void=("chamber",),
        pressure=pn.Pressure(inlet=("inlet",), zero=("outer", "fixed")),
        objective="mechanism",   # minimise -Δ/SE
        # the typical size of -Δ/SE (≈ 0.2 / (P_in L t)); the optimiser scales it to 10
        objective_ref=0.2 / (p.load * LENGTH * p.thickness),
    )


CASE = pn.Case(
    name="{name}",
    summary="soft finger with a round chamber, bends down under pressure",
    source="pacto new template",
    defaults=pn.Parameters(
        model="linear", maxh=0.0015, plane="strain", thickness=1e-3,
        E1=1e8, E0=1e2, nu=0.4, volfrac=0.35, filter_radius=0.004,
        penal_start=1.0, penal_step=0.04, beta=1.0, beta_max=16.0, beta_every=15,
        eta_k=0.2, eta_h=0.3, delta_s=0.002, load=1e5, k_out=1e4,
        iterations=160, move=0.05),
    geometry=geometry,
    setup=setup,
    load_unit="Pa",
)
'''


def write_template(name: str) -> Path:
    """Write the template as ``NAME.py`` (``NAME`` may be a path); never overwrites a file.

    The template is a case file of a soft finger with a round chamber (a netgen.occ geometry
    with named faces, edges and a vertex; supports, Darcy pressure, an output port with a
    spring, a passive void chamber; the mechanism objective) that runs as written.
    docs/tutorial.md builds the same case step by step.

    Parameters
    ----------
    name : str
        The case's name or the file's path (``.py`` is added when missing); the file's stem
        becomes the case's name (letters, digits, ``-`` and ``_``).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InputError
        An unusable name, an existing file, or a folder that does not exist.
    """
    path = Path(name if name.endswith(".py") else name + ".py")
    stem = path.stem
    if not stem.replace("_", "a").replace("-", "a").isalnum():
        raise InputError(f"new: '{name}' is not a usable case name (letters, digits, - and _)")
    if path.exists():
        raise InputError(f"new: '{path}' already exists (choose another name or remove it)")
    if not path.parent.is_dir():
        raise InputError(f"new: folder '{path.parent}' does not exist")
    atomic_write_text(path, TEMPLATE.format(name=stem, file=path.name))
    return path
