"""Benchmarks (JSON-line reports in the spirit of the paper's Table 1)."""
