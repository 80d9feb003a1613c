"""Benchmarks: speed/accuracy studies that write docs/benchmarks.md (not tests)."""
