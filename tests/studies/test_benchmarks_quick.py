"""The benchmark studies in their ``--quick`` mode (the smoke run of ``python -m benchmarks
all``): every study runs and writes its block of the report, and the peer study's two
implementations (ours and the numpy/scipy one) agree on the objective and the gradient.
Under ``pytest -m slow``: it takes about 110 s, a fifth of the default suite's time."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_benchmarks_all_quick(tmp_path):
    out = tmp_path / "benchmarks.md"
    r = subprocess.run([sys.executable, "-m", "benchmarks", "all", "--quick", "--out", str(out),
                        "--plots", str(tmp_path)], cwd=ROOT, capture_output=True, text=True,
                       timeout=900, env={**os.environ, "PACTO_THREADS": "1"})
    assert r.returncode == 0, r.stderr[-2000:]
    text = out.read_text()
    for name in ("peer", "trade", "stability", "profile", "mbb"):
        block = re.search(rf"<!-- BEGIN benchmarks-{name} -->(.*?)<!-- END benchmarks-{name} -->",
                          text, re.S)
        assert block is not None, name
        assert re.search(r"\| [0-9.e+-]+ \|", block.group(1)), name  # a table with numbers
    assert "VALIDATION FAILED" not in text
    assert (tmp_path / "trade_curves.png").stat().st_size > 0
