"""A field of a source mesh sampled at points: the pressure the remeshed part's boundaries are
wetted by (:mod:`.remesh`), the nodal ρ̄2 its elements take their material from
(:mod:`.materials`)."""
from __future__ import annotations

import numpy as np


def pressure_sampler(pressure, source):
    """A function ``(xy) -> p`` for points ``xy`` (n, 2); zero outside the source mesh.

    ``pressure`` may be an NGSolve CoefficientFunction or GridFunction on ``source``, a numpy
    array of nodal values (one per source vertex, the vertex order of ``source``), or a
    Python callable ``f(x, y)`` on arrays.
    """
    import ngsolve

    if isinstance(pressure, np.ndarray):
        vals = np.asarray(pressure, dtype=float).ravel()
        if vals.shape[0] != source.nv:
            raise ValueError(f"nodal pressure has {vals.shape[0]} values but the mesh has "
                             f"{source.nv} vertices")
        gf = ngsolve.GridFunction(ngsolve.H1(source, order=1))
        gf.vec.FV().NumPy()[:source.nv] = vals
        pressure = gf
    if isinstance(pressure, ngsolve.CoefficientFunction):
        cf = pressure

        def sample(xy):
            xy = np.atleast_2d(np.asarray(xy, dtype=float))
            mips = source(xy[:, 0].copy(), xy[:, 1].copy())
            out = np.zeros(len(xy))
            inside = mips["nr"] >= 0
            if inside.any():
                out[inside] = np.asarray(cf(mips[inside])).ravel()
            return out

        return sample
    if callable(pressure):
        return lambda xy: np.asarray(pressure(np.atleast_2d(xy)[:, 0], np.atleast_2d(xy)[:, 1]),
                                     dtype=float) * np.ones(len(np.atleast_2d(xy)))
    raise TypeError("pressure must be a CoefficientFunction, GridFunction, nodal array or callable")
