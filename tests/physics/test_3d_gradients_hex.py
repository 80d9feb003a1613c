"""Adjoint gradients of the whole 3D chain against central finite differences on structured
hexahedra: the set-up, references and tolerances of test_3d_gradients.py (tetrahedra)."""
from __future__ import annotations

import pytest

from test_3d_gradients import check_chain

pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.mark.parametrize("load", ["force", "fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean", "wang"])
def test_chain_gradients_on_hexahedra(model, load):
    check_chain("hex", model, load)
