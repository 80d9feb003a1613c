"""Run under ``mpirun -n N``: the chain of a case on a distributed mesh, at a given design.

``python3 mpi_chain.py CASE PARAMS.json DESIGN.npy OUT.npz``: DESIGN holds the serial design
vector; OUT gets (on rank 0) the objective, the constraints and their gradients, also in the
serial order (tests/parallel/test_mpi.py).
"""
import json
import sys

import numpy as np
from mpi4py import MPI

from pacto_ng.case import build_problem, get_case


def main(name, params_file, design_file, out_file):
    comm = MPI.COMM_WORLD
    case = get_case(name)
    with open(params_file) as fh:
        params = case.parameters(json.load(fh))
    problem = build_problem(case, params, comm=comm)
    f0, f, df0, df = problem.evaluate(np.load(design_file) if comm.rank == 0 else None)
    if comm.rank == 0:
        np.savez(out_file, f0=f0, f=f, df0=df0, df=df)


if __name__ == "__main__":
    main(*sys.argv[1:])
