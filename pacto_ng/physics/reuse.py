"""When a preconditioner built for one design's matrix serves the matrices of the next designs.

On the iterative route a linear system's BDDC is set up from the element matrices while its
form is assembled; the set-up is most of a design's cost beside the Krylov iterations
(cantilever-3d at order 2, 228,318 dofs, one thread: 5.4 s of a 9.7 s evaluation, against
1.1 s for the element matrices themselves; docs/studies.md, "A preconditioner kept across
designs").  From one optimisation iteration to the next the design changes little, so the
last design's BDDC stays a good preconditioner of the new matrix, which is then written from
the element matrices (:class:`~pacto_ng.physics.scatter.ElementMatrices`) without assembling
the form.  It is rebuilt where it has cost, in Krylov iterations beyond those of the design
it was built at, :data:`SETUP_ITERATIONS` in all: the iterations its set-up costs, so that
the iterations lost between two set-ups are at most one set-up's worth.  A solve with a kept
preconditioner that needs :attr:`Reuse.cap` iterations stops, and the preconditioner is
rebuilt for the rest; the next design is then built afresh, and after each further such solve
in a row twice as many (at most :data:`MAX_BACKOFF`): where the designs jump (a sharp
projection flips elements between solid and void) keeping costs more than it saves.
Measured on whole cantilever-3d runs: 7 % less wall time at 228,318 dofs, 12 % at 32,901, all
of it in the first half of the run (docs/studies.md).

The policy counts iterations, not seconds, so that a run repeats itself iteration for
iteration.
"""
from __future__ import annotations

#: a set-up of BDDC with its assembly, in Krylov iterations of the same system (the assembly
#: by the form less the element matrices' product, over one CG iteration): cantilever-3d at
#: order 2, one thread, (5.257 - 0.082) s / 62.6 ms = 83 at 228,318 dofs and (0.515 - 0.011)
#: s / 5.92 ms = 85 at 32,901
SETUP_ITERATIONS = 80
#: the most designs built afresh after solves that reached their cap
MAX_BACKOFF = 32


class Reuse:
    """The bookkeeping of a preconditioner kept across designs (see the module): the Krylov
    iterations of each design, against those of the design the preconditioner was built at."""

    def __init__(self):
        self.kept = False  # the preconditioner was built at an earlier design
        self.builds = 0  # set-ups (designs it was built at, and rebuilds within a solve)
        self.kept_designs = 0  # designs solved through with an earlier design's preconditioner
        self.rebuilt_in_solve = 0  # solves that needed it rebuilt (cap)
        self._base = None  # Krylov iterations of the first design solved with it (None: open)
        self._base_solve = 0  # ... the most of one solve there
        self._design = 0  # Krylov iterations of the current design
        self._excess = 0  # iterations beyond _base since it was built
        self._misses = 0  # solves in a row that reached their cap
        self._backoff = 0  # designs still to build afresh after them

    @property
    def due(self) -> bool:
        """Whether the next design's assembly should build the preconditioner anew."""
        return self.builds == 0 or self._excess >= SETUP_ITERATIONS or self._backoff > 0

    @property
    def cap(self) -> int | None:
        """The iterations a solve with a kept preconditioner may take before it is rebuilt
        (None: no solve has measured the preconditioner yet)."""
        if self._base_solve == 0:
            return None
        return max(2 * self._base_solve, self._base_solve + SETUP_ITERATIONS)

    def built(self, in_solve: bool = False):
        """The preconditioner was set up from the current design's matrix: at the design's
        assembly, or ``in_solve`` (a kept one reached its :attr:`cap`; the iterations of the
        design it was built at stay the reference)."""
        self.builds += 1
        self.kept = False
        self._excess = 0
        if in_solve:
            self.rebuilt_in_solve += 1
            self._misses += 1
            self._backoff = min(2 ** (self._misses - 1), MAX_BACKOFF)
        else:
            self._backoff = max(self._backoff - 1, 0)
            self._base, self._base_solve, self._design = None, 0, 0

    def count(self, iterations: int):
        """A solve of the current design took ``iterations``."""
        self._design += iterations
        if self._base is None:
            self._base_solve = max(self._base_solve, iterations)

    def new_design(self):
        """The design changes: the last design's iterations are weighed, and the preconditioner
        (if any) now belongs to an earlier design."""
        if self.builds == 0:
            return
        if self._base is None:
            if self._design > 0:  # (a design of no solve, e.g. the same design again, is none)
                self._base = self._design
        elif self.kept:
            self._excess += max(0, self._design - self._base)
        if self.kept:  # served through by a kept preconditioner
            self.kept_designs += 1
            self._misses = 0
        self._design = 0
        self.kept = True
