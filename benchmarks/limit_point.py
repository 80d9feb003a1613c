"""A pressure maximum followed: an inflated thick Neo-Hookean sphere against its closed form.

    python3 -m benchmarks limit_point [--out docs/studies.md]

An incompressible Neo-Hookean spherical shell (inner radius A = 1, outer B = 1.2, E = 1, shear
modulus μ = E / (2 (1 + ν))) inflated by a pressure P on its inner wall that follows the
deformation.  With λa = a/A and λb = b/B the stretches of the two walls (b³ - a³ = B³ - A³),
the radial equilibrium gives P = ∫_{λb}^{λa} W'(λ) / (λ³ - 1) dλ for the equibiaxial energy
W(λ) = μ/2 (2λ² + λ⁻⁴ - 3) (Ogden 1984, *Non-linear elastic deformations*, §5.3.1), that is
P/μ = (2/λb + 1/(2 λb⁴)) - (2/λa + 1/(2 λa⁴)): it rises to a maximum and falls after it, so a
pressure ramp cannot pass it.  The octant of the shell (symmetry planes held in their normal
direction) is meshed by Netgen at maxh h (curved, order 2) and analysed as a part is
(:class:`pacto_ng.post.part_analysis.PartAnalysis`: Neo-Hookean, the mixed formulation at
ν = 0.49999, follower pressure); the path is followed with the inner pole's radial motion
prescribed (:func:`pacto_ng.physics.path.trace`, 20 steps of 0.05 A, the same points on every
mesh) to A λa - A = 1, and the pressure maximum is found as a user's sweep finds it: a sweep
to 0.5 and 1.05 times the closed form's maximum (Newton loses the equilibrium at the second,
the sweep follows the path on in steps of a tenth of the motion reached and reports the
maximum of the parabola through the largest pressure and its neighbours,
:meth:`PartAnalysis.sweep`).  Each row: the
largest relative difference of P along the path from the closed form, the maximum's pressure
and position against the closed form's, and the seconds of the path and of the sweep on one
thread.
"""
from __future__ import annotations

import time

import numpy as np

A, B, NU = 1.0, 1.2, 0.49999
MU = 1.0 / (2.0 * (1.0 + NU))  # E = 1
SIZES = (0.2, 0.15, 0.1, 0.07)


def closed_form(la: float) -> float:
    """The inner pressure at the inner wall's stretch ``la`` (incompressible, the module's)."""
    lb = (1.0 + (la ** 3 - 1.0) * A ** 3 / B ** 3) ** (1.0 / 3.0)
    return MU * ((2.0 / lb + 0.5 / lb ** 4) - (2.0 / la + 0.5 / la ** 4))


def closed_peak() -> tuple[float, float]:
    """``(P, A λa - A)`` at the closed form's maximum."""
    from scipy.optimize import minimize_scalar

    r = minimize_scalar(lambda la: -closed_form(la), bounds=(1.01, 3.0), method="bounded")
    return -r.fun, (r.x - 1.0) * A


def sphere_octant(maxh: float):
    """The shell's octant, curved at order 2: inner wall "pressure", outer "free", symmetry
    planes "sym_x", "sym_y", "sym_z", the inner wall's point on the x axis "pole"."""
    from netgen.occ import Box, OCCGeometry, Pnt, Sphere
    from ngsolve import Mesh

    shell = (Sphere(Pnt(0, 0, 0), B) - Sphere(Pnt(0, 0, 0), A)) * Box(Pnt(0, 0, 0),
                                                                       Pnt(2, 2, 2))
    for f in shell.faces:
        c = f.center
        radius = max(np.linalg.norm([v.p.x, v.p.y, v.p.z]) for v in f.vertices)
        for axis, value in zip("xyz", (c.x, c.y, c.z)):
            if abs(value) < 1e-9:
                f.name = f"sym_{axis}"
                break
        else:
            f.name = "pressure" if radius < 0.5 * (A + B) else "free"
    for v in shell.vertices:
        if np.allclose([v.p.x, v.p.y, v.p.z], [A, 0, 0]):
            v.name = "pole"
    mesh = Mesh(OCCGeometry(shell).GenerateMesh(maxh=maxh))
    mesh.Curve(2)
    return mesh


def inflated(mesh):
    """The shell's analysis as a part's (the module's settings)."""
    from pacto_ng.params import Parameters
    from pacto_ng.physics.loads import Port
    from pacto_ng.physics.mechanics import Supports
    from pacto_ng.post.part_analysis import PartAnalysis

    params = Parameters(model="neohookean", E1=1.0, E0=1e-6, nu=NU, order=2,
                        formulation="mixed")
    return PartAnalysis(mesh, "follower", params=params,
                        supports=Supports(fix_x=("sym_x",), fix_y=("sym_y",),
                                          fix_z=("sym_z",)),
                        ports=(Port("pole", (1.0, 0.0, 0.0)),))


def one(maxh: float) -> dict:
    from pacto_ng.physics.path import trace

    mesh = sphere_octant(maxh)
    ana = inflated(mesh)
    mech = ana.mech
    mech.set_fields(*ana.solid_values())
    t0 = time.perf_counter()
    path = trace(mech, mech.gfx.vec, ana.output_form, 0.05, mech.settings,
                 stop=lambda q: q.control >= 1.0 - 1e-9, max_step=0.05)
    t_path = time.perf_counter() - t0
    err = max(abs(q.load / closed_form(1.0 + q.control / A) - 1.0) for q in path)
    peak, at = closed_peak()
    t0 = time.perf_counter()
    sweep = inflated(mesh).sweep([0.5 * peak, 1.05 * peak])
    t_sweep = time.perf_counter() - t0
    return {"maxh": maxh, "elements": mesh.ne, "path_error": err,
            "peak": sweep.peak["pressure"] / peak - 1.0, "at": sweep.peak["delta"] - at,
            "t_path": t_path, "t_sweep": t_sweep, "points": len(path)}


def report(rows: list[dict]) -> str:
    peak, at = closed_peak()
    lines = ["| maxh | tetrahedra | largest P difference along the path | maximum's P | "
             "maximum's position (A λa − A) | path (points, s) | sweep past the maximum (s) |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['maxh']:g} | {r['elements']} | {r['path_error']:.2e} | "
                     f"{r['peak']:+.2e} | {r['at']:+.4f} | {r['points']}, {r['t_path']:.1f} | "
                     f"{r['t_sweep']:.1f} |")
    rates = [np.log(a["path_error"] / b["path_error"]) / np.log(a["maxh"] / b["maxh"])
             for a, b in zip(rows, rows[1:])]
    return ("\n".join(lines) + f"\n\nThe closed form's maximum: P = {peak:.6f} at A λa − A = "
            f"{at:.4f}.  Observed orders of the path's difference between successive sizes: "
            + ", ".join(f"{r:.2f}" for r in rates) + ".\n")


def main(argv=None):
    from benchmarks.__main__ import standalone

    standalone(argv, "limit_point", "A pressure maximum followed: the inflated thick sphere", __doc__, SIZES, one, report)


if __name__ == "__main__":
    main()
