"""Every built-in optimisation case quotes its chain in its docstring, as ``pacto run CASE
--show-chain`` builds and prints it (so that the quote cannot go stale)."""
import importlib

import pytest

from pacto_ng.case import CASE_MODULES, get_case
from pacto_ng.cli import main

OPTIMISATIONS = [name for name in CASE_MODULES if not get_case(name).analysis_only]


@pytest.mark.parametrize("name", OPTIMISATIONS)
def test_the_docstring_quotes_the_chain_the_case_builds(name, capsys):
    # uncompiled forms: the chain is the same, and the build takes a second, not a compile's
    assert main(["run", name, "--show-chain", "--set", "realcompile=0"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith(f"{name} (")
    chain = [line.strip() for line in printed[1:] if line.strip()]
    assert len(chain) >= 4  # blocks from the design to the objective, and the summary line
    doc = importlib.import_module(CASE_MODULES[name]).__doc__
    head = f"Its chain (``pacto run {name} --show-chain``)::"
    assert head in doc
    # the quote, its whitespace aside (the summary line may wrap)
    quoted = " ".join(doc.split(head, 1)[1].split())
    assert quoted.startswith(" ".join(" ".join(chain).split()))


def test_an_analysis_case_has_no_chain_to_quote():
    assert "c-beam" in CASE_MODULES and "c-beam" not in OPTIMISATIONS
