"""Volumetric locking: the displacement formulation against the mixed one as ν -> 1/2.

    python3 -m benchmarks locking [--out docs/studies.md] [--plot docs/img/locking.png]

A Neo-Hookean cantilever in plane strain (1 x 0.25 m, clamped on the left, a downward load of
20 N spread over the right edge, t = 0.1 m, E = 1 MPa: a tip deflection of about 4 % of the
length) on structured quadrilaterals (Q1, 32 x 8) and Netgen triangles (P2, h = 0.0625), at
ν from 0.3 to 0.4999.  The reference is the mixed formulation on the structured mesh refined
four times (Q1/P0, 128 x 32), whose convergence the table shows at ν = 0.3 against the
displacement formulation on the same fine mesh (which does not lock there).  Newton to a
residual of 1e-10 of the load; the time is one forward solve (assembly, factorisations) on one
thread.
"""
from __future__ import annotations

import argparse
import os
import time

NUS = (0.3, 0.4, 0.45, 0.49, 0.499, 0.4999)


def tip(nu: float, formulation: str, mesh_kind: str, n: int) -> tuple[float, int, float]:
    """(tip deflection, Newton iterations, seconds) of the cantilever."""
    from pacto_ng.mesh import Layout, Segment, netgen_mesh, structured_mesh
    from pacto_ng.physics.loads import PointLoad
    from pacto_ng.physics.materials import jacobian, neohookean_energy
    from pacto_ng.physics.mechanics import Mechanics, Supports
    from pacto_ng.physics.newton import NewtonSettings

    lay = Layout(1.0, 0.25, segments=(Segment("fixed", (0.0, 0.0), (0.0, 0.25)),
                                      Segment("load", (1.0, 0.0), (1.0, 0.25))))
    if mesh_kind == "quad":
        mesh, order = structured_mesh(lay, 4 * n, n), 1
    else:
        mesh, order = netgen_mesh(lay, 0.25 / n), 2
    mech = Mechanics(mesh, order=order, energy=lambda G, c: neohookean_energy(G, 1e6, nu),
                     fields=(), supports=Supports(clamp=("fixed",)),
                     loads=(PointLoad("load", (0.0, -20.0)),), thickness=0.1,
                     guard=lambda G, c: jacobian(G), newton=NewtonSettings(rtol=1e-10),
                     formulation=formulation)
    start = time.perf_counter()
    mech.forward()
    seconds = time.perf_counter() - start
    return -mech.gfu(mesh(1.0, 0.125))[1], mech.result.iterations, seconds


def study() -> list[dict]:
    rows = []
    for nu in NUS:
        ref = tip(nu, "mixed", "quad", 32)[0]
        row = {"nu": nu, "reference": ref}
        for kind, n in (("quad", 8), ("trig", 4)):
            for form in ("displacement", "mixed"):
                d, its, sec = tip(nu, form, kind, n)
                row[f"{kind}_{form}"] = (d, its, sec)
        if nu == NUS[0]:
            row["fine_displacement"] = tip(nu, "displacement", "quad", 32)[0]
        print(row, flush=True)
        rows.append(row)
    return rows


def report(rows: list[dict], plot: str | None) -> str:
    head = ("| ν | reference | Q1 displacement | Q1/P0 mixed | P2 displacement | P2+/P1 mixed |\n"
            "|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        cells = [f"{r['nu']:g}", f"{r['reference']:.5f}"]
        for key in ("quad_displacement", "quad_mixed", "trig_displacement", "trig_mixed"):
            d, its, sec = r[key]
            cells.append(f"{d:.5f} ({100 * (d / r['reference'] - 1):+.1f} %, {its} it, "
                         f"{sec:.2f} s)")
        lines.append("| " + " | ".join(cells) + " |")
    fine = rows[0].get("fine_displacement")
    text = (head + "\n".join(lines) + "\n\n"
            f"Each cell: tip deflection (m), its difference from the reference, Newton "
            f"iterations, seconds.  Reference check at ν = {rows[0]['nu']:g}: the displacement "
            f"formulation on the fine mesh gives {fine:.5f}, "
            f"{100 * (fine / rows[0]['reference'] - 1):+.2f} % from the mixed one.\n")
    if plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        x = [0.5 - r["nu"] for r in rows]
        ax.semilogx(x, [r["reference"] for r in rows], "k-", label="reference (Q1/P0, 128 x 32)")
        for key, style, label in (("quad_displacement", "o--", "Q1 displacement, 32 x 8"),
                                  ("quad_mixed", "o-", "Q1/P0 mixed, 32 x 8"),
                                  ("trig_displacement", "s--", "P2 displacement, h = 1/16"),
                                  ("trig_mixed", "s-", "P2+/P1 mixed, h = 1/16")):
            ax.semilogx(x, [r[key][0] for r in rows], style, label=label)
        ax.invert_xaxis()
        ax.set_xlabel("0.5 - ν")
        ax.set_ylabel("tip deflection (m)")
        ax.set_title("Neo-Hookean cantilever, plane strain")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(plot, dpi=110)
        text += f"\n![locking]({os.path.relpath(plot, 'docs')})\n"
    return text


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join("docs", "studies.md"))
    ap.add_argument("--plot", default=os.path.join("docs", "img", "locking.png"))
    args = ap.parse_args(argv)
    from benchmarks.__main__ import machine, replace_block

    mach = machine()
    print(f"[locking] {mach}", flush=True)
    rows = study()
    body = ("## Volumetric locking: displacement against mixed\n\n"
            "`python3 -m benchmarks locking` (" + mach + ").  " + __doc__.split("\n\n")[1]
            .replace("\n", " ") + "\n\n" + report(rows, args.plot))
    replace_block(args.out, "benchmarks-locking", body)
    print(body)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
