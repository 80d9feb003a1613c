"""Peer comparison: one analysis with sensitivities of the linear pressure-actuated inverter.

    python -m benchmarks.peer_pa_inverter [--sizes 60x40,120x80,240x160] [--repeat 3]

The set-up of the published MATLAB soft-robot codes: structured Q1 meshes of unit square
elements, plane stress, E1 = 1, E0 = 1e-6, ν = 0.3, t = 1, P_in = 1, Δs = 2 element units, a
cone density filter of radius 2.4, SIMP p = 3, no projection, output spring k_out = 0.1.
One "analysis with sensitivities" = filter, Darcy solve, load, elasticity solve, one adjoint
solve of each (the combined adjoint of the objective -Δ/SE), element sensitivities.

*ours*: the NGSolve chain, ``problem.evaluate(x)`` (objective, volume and both gradients).
*peer*: :class:`ScipyPAInverter`, a plain numpy/scipy implementation of the same discretisation
written for this benchmark only (Q1 element matrices, ``scipy.sparse`` assembly once per
evaluation, ``scipy.sparse.linalg.splu`` factorisations reused for the adjoints).

First both are evaluated on the same design and must agree (objective to 1e-8 relative,
gradient to 1e-6 relative in the max norm): that validates both.  Then the median wall time of
``--repeat`` evaluations of each (after one warm-up).

``order_study``: for a fixed design on the physical 0.2 x 0.1 m domain (a piecewise-constant
design on a 30 x 15 grid, exactly representable on every finer structured mesh, no filter), the
objective at Q1/Q2/Q3 on refined meshes against the finest Q1 mesh; the cheapest Q2/Q3 mesh
that matches it to a tolerance, with times.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from benchmarks import perturbed

# the benchmark set-up (element units)
SETUP = dict(E1=1.0, E0=1e-6, nu=0.3, t=1.0, P_in=1.0, delta_s=2.0, r=0.1, Kv=1.0, Ks=1e-7,
             eta_k=0.3, beta_k=10.0, eta_h=0.2, beta_h=10.0, rmin=2.4, penal=3.0, k_out=0.1)


def ours_params(nelx, nely, order=1):
    s = SETUP
    return {"nelx": str(nelx), "nely": str(nely), "unit_elements": "1", "plane": "stress",
            "E1": str(s["E1"]), "E0": str(s["E0"]), "nu": str(s["nu"]),
            "thickness": str(s["t"]), "load": str(s["P_in"]), "delta_s": str(s["delta_s"]),
            "r": str(s["r"]), "Kv": str(s["Kv"]), "Ks": str(s["Ks"]),
            "filter": "cone", "filter_radius": str(s["rmin"]), "beta": "0", "beta_max": "0",
            "penal": str(s["penal"]), "penal_start": "0", "k_out": str(s["k_out"]),
            "order": str(order)}


def test_design(xy, L, H):
    """A fixed, non-trivial design in [0.05, 0.95] as a function of position."""
    X, Y = xy[:, 0] / L, xy[:, 1] / H
    return np.clip(0.45 + 0.4 * np.sin(3 * np.pi * X) * np.cos(2 * np.pi * Y)
                   + 0.1 * np.cos(7 * X + 3 * Y), 0.05, 0.95)


# ------------------------------------------------------------------------------------------
def _heaviside(rho, eta, beta):
    den = np.tanh(beta * eta) + np.tanh(beta * (1 - eta))
    return (np.tanh(beta * eta) + np.tanh(beta * (rho - eta))) / den


def _dheaviside(rho, eta, beta):
    den = np.tanh(beta * eta) + np.tanh(beta * (1 - eta))
    return beta * (1 - np.tanh(beta * (rho - eta)) ** 2) / den


def q1_element_matrices(nu):
    """Unit-square Q1 matrices: elasticity (E = 1, plane stress), Laplace, mass, and the
    load coupling ``He[2i+c, j] = ∫ N_i ∂_c N_j`` (2 x 2 Gauss, exact here)."""
    g = np.array([-1, 1]) / np.sqrt(3) * 0.5 + 0.5
    corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    D = 1 / (1 - nu ** 2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    Ke = np.zeros((8, 8)); Le = np.zeros((4, 4)); Me = np.zeros((4, 4)); He = np.zeros((8, 4))
    for xi in g:
        for eta in g:
            N = np.array([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta])
            dN = np.array([[-(1 - eta), -(1 - xi)], [1 - eta, -xi], [eta, xi], [-eta, 1 - xi]])
            B = np.zeros((3, 8))
            B[0, 0::2] = dN[:, 0]; B[1, 1::2] = dN[:, 1]
            B[2, 0::2] = dN[:, 1]; B[2, 1::2] = dN[:, 0]
            w = 0.25
            Ke += w * B.T @ D @ B
            Le += w * dN @ dN.T
            Me += w * np.outer(N, N)
            for c in range(2):
                He[c::2, :] += w * np.outer(N, dN[:, c])
    assert np.allclose(corners.sum(), 4)
    return Ke, Le, Me, He


class ScipyPAInverter:
    """Plain numpy/scipy reference of the unit-element pressure-actuated inverter (benchmark)."""

    def __init__(self, nelx, nely, s=SETUP, permc="MMD_AT_PLUS_A"):
        self.nelx, self.nely, self.s, self.permc = nelx, nely, s, permc
        ne = nelx * nely
        self.Ke, self.Le, self.Me, self.He = q1_element_matrices(s["nu"])
        I, J = np.meshgrid(np.arange(nelx), np.arange(nely))  # element (i, j) -> j*nelx + i
        I, J = I.ravel(), J.ravel()
        nid = lambda i, j: j * (nelx + 1) + i
        self.enod = np.stack([nid(I, J), nid(I + 1, J), nid(I + 1, J + 1), nid(I, J + 1)], 1)
        self.edof = np.repeat(2 * self.enod, 2, axis=1) + np.tile([0, 1], 4)
        self.nn = (nelx + 1) * (nely + 1)
        # sparse patterns
        self.iK = np.repeat(self.edof, 8, 1).ravel(); self.jK = np.tile(self.edof, 8).ravel()
        self.iP = np.repeat(self.enod, 4, 1).ravel(); self.jP = np.tile(self.enod, 4).ravel()
        self.iH = np.repeat(self.edof, 4, 1).ravel(); self.jH = np.tile(self.enod, 8).ravel()
        # passive block L/20 x H/20 under the clamp (top-left), by centroid
        L, H = float(nelx), float(nely)
        cx, cy = I + 0.5, J + 0.5
        self.solid = (cx <= L / 20) & (cy >= H - H / 20)
        self.design = ~self.solid
        # Darcy Dirichlet: inlet x = 0 -> P_in, top and right -> 0 (zero wins at shared nodes)
        ni, nj = np.meshgrid(np.arange(nelx + 1), np.arange(nely + 1))
        ni, nj = ni.ravel(), nj.ravel()
        zero = (nj == nely) | (ni == nelx)
        inlet = (ni == 0) & ~zero
        self.p_fixed = zero | inlet
        self.p_lift = np.where(inlet, s["P_in"], 0.0)
        self.p_free = np.flatnonzero(~self.p_fixed)
        # mechanics: clamp on the top edge x <= L/20, u_y = 0 on y = 0
        clamp = (nj == nely) & (ni <= L / 20 + 1e-9)
        fixed = np.zeros(2 * self.nn, bool)
        fixed[2 * np.flatnonzero(clamp)] = True; fixed[2 * np.flatnonzero(clamp) + 1] = True
        fixed[2 * np.flatnonzero(nj == 0) + 1] = True
        self.u_free = np.flatnonzero(~fixed)
        self.out = 2 * nid(nelx, 0)  # u_x at the bottom-right corner
        # cone filter (top88 style, radius rmin, equal areas)
        cen = np.stack([cx, cy], 1)
        from scipy.spatial import cKDTree
        tree = cKDTree(cen)
        d = tree.sparse_distance_matrix(tree, s["rmin"], output_type="coo_matrix")
        w = s["rmin"] - d.data
        off = (w > 0) & (d.row != d.col)
        Wm = sp.coo_matrix((w[off], (d.row[off], d.col[off])), shape=(ne, ne)).tocsr()
        Wm = Wm + sp.diags(np.full(ne, s["rmin"]))
        self.Hf = (sp.diags(1 / np.asarray(Wm.sum(1)).ravel()) @ Wm).tocsr()
        self.HfT = self.Hf.T.tocsr()
        self.drain = (np.log(s["r"]) / s["delta_s"]) ** 2 * s["Ks"]

    def evaluate(self, x):
        """Objective -Δ/SE and its gradient w.r.t. the design variables (plus Δ and SE)."""
        s, t = self.s, self.s["t"]
        rho = np.ones(len(self.design)); rho[self.design] = x
        rb = self.Hf @ rho
        rb[self.solid] = 1.0
        # Darcy
        Kf = s["Kv"] - (s["Kv"] - s["Ks"]) * _heaviside(rb, s["eta_k"], s["beta_k"])
        Dd = self.drain * _heaviside(rb, s["eta_h"], s["beta_h"])
        vals = (np.outer(Kf, self.Le.ravel()) + np.outer(Dd, self.Me.ravel())).ravel()
        A = sp.csc_matrix((vals, (self.iP, self.jP)), shape=(self.nn, self.nn))
        fr = self.p_free
        Aff = A[fr][:, fr].tocsc()
        luA = spla.splu(Aff, permc_spec=self.permc)
        p = self.p_lift.copy()
        p[fr] = luA.solve(-(A @ self.p_lift)[fr])
        # load F = -t H p
        Hg = sp.csc_matrix((np.tile(self.He.ravel(), len(rb)), (self.iH, self.jH)),
                           shape=(2 * self.nn, self.nn))
        F = -t * (Hg @ p)
        # elasticity
        E = s["E0"] + rb ** s["penal"] * (s["E1"] - s["E0"])
        dE = s["penal"] * rb ** (s["penal"] - 1) * (s["E1"] - s["E0"])
        K0 = sp.csc_matrix((np.outer(t * E, self.Ke.ravel()).ravel(), (self.iK, self.jK)),
                           shape=(2 * self.nn, 2 * self.nn))
        K = K0 + sp.csc_matrix(([s["k_out"]], ([self.out], [self.out])), shape=K0.shape)
        uf = self.u_free
        luK = spla.splu(K[uf][:, uf].tocsc(), permc_spec=self.permc)
        u = np.zeros(2 * self.nn)
        u[uf] = luK.solve(F[uf])
        ue = u[self.edof]
        ce = np.einsum("ei,ij,ej->e", ue, self.Ke, ue)
        se = 0.5 * t * float(E @ ce)
        delta = -u[self.out]
        f0 = -delta / se
        # combined adjoint of f0 = -Δ/SE: K λ = ∂f0/∂u
        dfdu = (delta / se ** 2) * (K0 @ u)
        dfdu[self.out] += 1.0 / se
        lam = np.zeros_like(u)
        lam[uf] = luK.solve(dfdu[uf])
        le = lam[self.edof]
        # explicit + through E: ∂f0/∂SE ∂SE/∂ρ - λᵀ ∂R/∂ρ with R = K u - F(p)
        g = (delta / se ** 2) * 0.5 * t * dE * ce - t * dE * np.einsum("ei,ij,ej->e", le,
                                                                       self.Ke, ue)
        # through p: ∂R/∂p = t Hg; Darcy adjoint A μ = -(t Hgᵀ λ)
        dfdp = -t * (Hg.T @ lam)
        mu = np.zeros(self.nn)
        mu[fr] = luA.solve(dfdp[fr])
        pe, me = p[self.enod], mu[self.enod]
        dK = -(s["Kv"] - s["Ks"]) * _dheaviside(rb, s["eta_k"], s["beta_k"])
        dD = self.drain * _dheaviside(rb, s["eta_h"], s["beta_h"])
        g -= dK * np.einsum("ei,ij,ej->e", me, self.Le, pe) + dD * np.einsum(
            "ei,ij,ej->e", me, self.Me, pe)
        g[self.solid] = 0.0
        grad = (self.HfT @ g)[self.design]
        return f0, grad, delta, se


# ------------------------------------------------------------------------------------------
def _median_time(fn, designs, repeat):
    """Median time of ``fn(x)`` over ``repeat`` calls, each on the other of two designs than
    the call before (as in an optimisation: every evaluation is a new design, so a warm-started
    solve cannot find the state already in equilibrium); after one warm-up."""
    fn(designs[1])  # warm-up: first factorisation, compilation, and (at the second design)
    fn(designs[0])  # the element matrices of the linear path
    ts = []
    for k in range(repeat):
        x = designs[k % 2]
        t0 = time.perf_counter()
        fn(x)
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def _designs(x):
    """The design and a perturbed one (:func:`benchmarks.perturbed`)."""
    return [x, perturbed(x)]


def compare(nelx, nely, repeat=3):
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case

    case = get_case("pa-inverter")
    params = case.defaults.with_overrides(ours_params(nelx, nely))
    peer = ScipyPAInverter(nelx, nely)
    with compute(threads=2):
        problem = build_problem(case, params)
        cen = problem.field.centroids()[problem.field.design_index]
        x = test_design(cen, nelx, nely)
        # the same element order: NGSolve element j*nelx + i = ours; check the passive set
        assert np.array_equal(problem.field.solid, peer.solid), "passive sets differ"
        f_ours, _, g_ours, _ = problem.evaluate(x)
        vals = problem.values
        d_ours, se_ours = float(vals["delta"]), float(vals["se"])
        f_peer, g_peer, d_peer, se_peer = peer.evaluate(x)
        xs = _designs(x)
        t_ours = _median_time(problem.evaluate, xs, repeat)
        ndof = problem.mech.fes.ndof + problem.pressure_block.fes.ndof
    # one NGSolve thread as well (the scipy peer's splu runs on one)
    with compute(threads=1):
        t_ours1 = _median_time(problem.evaluate, xs, repeat)
    t_peer = _median_time(peer.evaluate, xs, repeat)
    return dict(mesh=f"{nelx} x {nely}", dofs=ndof, f_ours=f_ours, f_peer=f_peer,
                rel_f=abs(f_ours - f_peer) / abs(f_peer),
                rel_delta=abs(d_ours - d_peer) / abs(d_peer),
                rel_se=abs(se_ours - se_peer) / abs(se_peer),
                rel_grad=float(np.max(np.abs(g_ours - g_peer)) / np.max(np.abs(g_peer))),
                t_ours=t_ours, t_ours1=t_ours1, t_peer=t_peer, ratio=t_peer / t_ours,
                ratio1=t_peer / t_ours1)


# ------------------------------------------------------------------------------------------
#: the spread output of the order study: the right edge's first H/15 (one cell of the design
#: grid, a grid line of every mesh of the study)
SPREAD_OUTPUT = 0.1 / 15


def _physical_params(nelx, nely, order, k_out=0.1, output_width=0.0):
    """The physical pa-inverter domain (0.2 x 0.1 m, plane stress, E1 = 1) on a structured mesh,
    no filter, no projection (the design is exactly the same function on every mesh)."""
    return {"nelx": str(nelx), "nely": str(nely), "plane": "stress", "E1": "1", "E0": "1e-6",
            "nu": "0.3", "thickness": "1", "load": "1", "delta_s": "0.01", "filter": "none",
            "beta": "0", "beta_max": "0", "penal": "3", "penal_start": "0", "k_out": str(k_out),
            "order": str(order), "output_width": repr(float(output_width))}


def coarse_design(cen, L=0.2, H=0.1, nx=30, ny=15):
    """A piecewise-constant design on an nx x ny grid (representable on nested meshes)."""
    i = np.minimum((cen[:, 0] / L * nx).astype(int), nx - 1)
    j = np.minimum((cen[:, 1] / H * ny).astype(int), ny - 1)
    c = np.stack([(i + 0.5) * L / nx, (j + 0.5) * H / ny], 1)
    return test_design(c, L, H)


def order_point(nelx, nely, order, repeat=3, k_out=0.1, output_width=0.0):
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case

    case = get_case("pa-inverter")
    params = case.defaults.with_overrides(_physical_params(nelx, nely, order, k_out,
                                                           output_width))
    with compute(threads=1):  # as the scipy peer: one thread
        problem = build_problem(case, params)
        cen = problem.field.centroids()[problem.field.design_index]
        x = coarse_design(cen)
        f0 = problem.evaluate(x)[0]
        t = _median_time(problem.evaluate, _designs(x), repeat)
        ndof = problem.mech.fes.ndof + problem.pressure_block.fes.ndof
    return dict(mesh=f"{nelx} x {nely}", nelx=nelx, order=order, dofs=ndof, f=f0, time=t)


def order_study(levels=(30, 60, 120, 240), fine=480, orders=(1, 2, 3), tol=1e-2, repeat=3,
                max_dofs=400_000, k_out=0.1, output_width=0.0):
    """Objective of a fixed design per (mesh, order) against the finest Q1 mesh."""
    ref = order_point(fine, fine // 2, 1, repeat=1, k_out=k_out, output_width=output_width)
    rows = []
    for k in orders:
        for n in levels:
            if n >= fine and k == 1:
                continue
            est = 3 * (k * n + 1) * (k * n // 2 + 1)
            if est > max_dofs:
                continue
            r = order_point(n, n // 2, k, repeat, k_out=k_out, output_width=output_width)
            r["err"] = abs(r["f"] - ref["f"]) / abs(ref["f"])
            rows.append(r)
    picks = {}
    for k in orders:
        ok = [r for r in rows if r["order"] == k and r["err"] <= tol]
        if ok:
            picks[k] = min(ok, key=lambda r: r["time"])
    return ref, rows, picks


def peer_time(nelx, nely, repeat=3):
    """Median time of one evaluation of the scipy peer on an nelx x nely Q1 mesh (the same
    matrix sizes as our Q1 run on that mesh; unit elements)."""
    peer = ScipyPAInverter(nelx, nely)
    I, J = np.meshgrid(np.arange(nelx), np.arange(nely))
    cen = np.stack([I.ravel() + 0.5, J.ravel() + 0.5], 1)[peer.design]
    return _median_time(peer.evaluate, _designs(test_design(cen, nelx, nely)), repeat)


def equal_accuracy(ref, rows, tols=(1e-3, 3e-4), repeat=3, peer=True):
    """For each tolerance: the cheapest run of each order whose error against the best estimate
    (the highest order on its finest mesh) is within it *on that mesh and every finer one of
    the same order* (so that a lucky crossing of an oscillating sequence does not count); the
    time of order 2 and 3 against our Q1 and against the scipy peer on the Q1 mesh."""
    allrows = rows + [dict(ref, order=1)]
    best = max(rows, key=lambda r: (r["order"], r["dofs"]))
    err = lambda r: abs(r["f"] - best["f"]) / abs(best["f"])
    out = []
    for tol in tols:
        picks = {}
        for k in (1, 2, 3):
            seq = sorted((r for r in allrows if r["order"] == k and r is not best),
                         key=lambda r: r["dofs"])
            for i, r in enumerate(seq):
                if all(err(q) <= tol for q in seq[i:]):
                    picks[k] = r
                    break
        entry = {"tol": tol, "picks": picks, "best": best}
        q1 = picks.get(1)
        if q1 is not None and peer:
            entry["peer_time"] = peer_time(q1["nelx"], q1["nelx"] // 2, repeat)
        out.append(entry)
    return out


def decrement_line(ref, rows, order=1):
    """The objective's change per halving of h for one order: a change that stays the same from
    one halving to the next is a logarithmic divergence, one that halves (or faster) converges."""
    seq = sorted((r for r in rows + [dict(ref, order=1)] if r["order"] == order),
                 key=lambda r: r["dofs"])
    d = [b["f"] - a["f"] for a, b in zip(seq, seq[1:])]
    if len(d) < 2:
        return ""
    ratios = ", ".join(f"{b / a:.2f}" for a, b in zip(d, d[1:]) if a != 0)
    return (f"- order {order}: change of the objective per halving of h "
            f"{', '.join(f'{x:+.4g}' for x in d)} ({seq[0]['mesh']} → {seq[-1]['mesh']}); "
            f"ratio of successive changes {ratios} (about 0.5 or less: converging; near 1: "
            f"growing like log(1/h))")


def equal_accuracy_markdown(entries):
    out = []
    for e in entries:
        picks, q1 = e["picks"], e["picks"].get(1)
        best = e["best"]
        line = f"- within {e['tol']:.0e} of the best estimate (order {best['order']} on {best['mesh']}): "
        parts = []
        for k in (1, 2, 3):
            r = picks.get(k)
            parts.append(f"order {k}: " + ("none in the study" if r is None else
                                           f"{r['mesh']}, {r['dofs']} dofs, {r['time']:.3f} s"))
        line += "; ".join(parts)
        if q1 is not None:
            ratios = []
            for k in (2, 3):
                r = picks.get(k)
                if r is None:
                    continue
                txt = f"order {k} is {q1['time'] / r['time']:.1f}x faster than our Q1"
                if "peer_time" in e:
                    txt += (f" and {e['peer_time'] / r['time']:.1f}x faster than the scipy Q1 "
                            f"peer on {q1['mesh']} ({e['peer_time']:.3f} s)")
                ratios.append(txt)
            if ratios:
                line += " — " + "; ".join(ratios)
        out.append(line)
    return "\n".join(out)


# ------------------------------------------------------------------------------------------
def peer_markdown(rows):
    out = ["| mesh | dofs (u + p) | objective ours | objective scipy | rel. diff objective | "
           "rel. diff Δ, SE | rel. diff gradient (max) | ours, 2 threads [s] | ours, 1 thread [s] | "
           "scipy [s] | scipy / ours (2 thr.) | scipy / ours (1 thr.) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['mesh']} | {r['dofs']} | {r['f_ours']:.10g} | {r['f_peer']:.10g} | "
                   f"{r['rel_f']:.1e} | {r['rel_delta']:.1e}, {r['rel_se']:.1e} | "
                   f"{r['rel_grad']:.1e} | {r['t_ours']:.3f} | {r['t_ours1']:.3f} | {r['t_peer']:.3f} | "
                   f"**{r['ratio']:.2f}** | **{r['ratio1']:.2f}** |")
    return "\n".join(out)


def order_markdown(ref, rows, picks, tol, fine_q1_lines=True):
    """Table of the order study.  Besides the error against the fine Q1 run, the difference
    from the best estimate (the highest order on its finest mesh): fine Q1 is itself only
    first-order accurate, so the question "which coarse P2/P3 run is as accurate as fine Q1"
    is answered against that estimate."""
    best = max(rows, key=lambda r: (r["order"], r["dofs"]))
    e_ref = abs(ref["f"] - best["f"]) / abs(best["f"])
    out = [f"Reference: Q1 on {ref['mesh']} ({ref['dofs']} dofs), objective {ref['f']:.8g}, "
           f"{ref['time']:.3f} s (one evaluation, no repeat).  Best estimate: order "
           f"{best['order']} on {best['mesh']}, objective {best['f']:.8g}; the fine Q1 "
           f"reference differs from it by {e_ref:.2e}.", "",
           "| order | mesh | dofs (u + p) | objective | rel. error vs fine Q1 | "
           "rel. diff vs best estimate | time [s] |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        e_best = abs(r["f"] - best["f"]) / abs(best["f"])
        out.append(f"| {r['order']} | {r['mesh']} | {r['dofs']} | {r['f']:.8g} | "
                   f"{r['err']:.2e} | {'–' if r is best else format(e_best, '.2e')} | "
                   f"{r['time']:.3f} |")
    out.append("")
    q1 = picks.get(1)
    for k, r in sorted(picks.items() if fine_q1_lines else ()):
        line = (f"- cheapest order-{k} mesh within {tol:.0e} of the fine Q1 objective: "
                f"{r['mesh']} ({r['dofs']} dofs, {r['time']:.3f} s")
        if q1 is not None and k != 1:
            line += f"; {q1['time'] / r['time']:.2f}x faster than the cheapest Q1 ({q1['mesh']})"
        out.append(line + ")")
    missing = [k for k in (1, 2, 3) if k not in picks]
    if missing and fine_q1_lines:
        out.append(f"- no mesh of order {', '.join(map(str, missing))} in the study is within "
                   f"{tol:.0e} of the fine Q1 objective")
    # how far each order is from convergence: the change between its two finest meshes
    steps = []
    for k in (1, 2, 3):
        seq = sorted((r for r in rows + ([dict(ref, order=1)] if k == 1 else [])
                      if r["order"] == k), key=lambda r: r["dofs"])
        if len(seq) >= 2:
            a, b = seq[-2], seq[-1]
            steps.append(f"order {k} {a['mesh']} → {b['mesh']}: "
                         f"{abs(b['f'] - a['f']) / abs(b['f']):.1%}")
    if steps:
        out.append("- change of the objective between the two finest meshes of each order: "
                   + "; ".join(steps))
    for k in (2, 3) if fine_q1_lines else ():
        ok = [r for r in rows if r["order"] == k and r is not best
              and abs(r["f"] - best["f"]) / abs(best["f"]) <= e_ref]
        if ok:
            r = min(ok, key=lambda r: r["time"])
            out.append(f"- as close to the best estimate as fine Q1 (or closer) with order {k}: "
                       f"{r['mesh']} ({r['dofs']} dofs) in {r['time']:.3f} s, "
                       f"{ref['time'] / r['time']:.2f}x the speed of fine Q1")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="60x40,120x80,240x160")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-orders", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    for s in args.sizes.split(","):
        nx, ny = (int(v) for v in s.split("x"))
        rows.append(compare(nx, ny, args.repeat))
        print(peer_markdown(rows[-1:]), flush=True)
    print(peer_markdown(rows))
    if not args.no_orders:
        ref, orows, picks = order_study(repeat=args.repeat)
        print(order_markdown(ref, orows, picks, 1e-2))
    return rows


if __name__ == "__main__":
    main()
