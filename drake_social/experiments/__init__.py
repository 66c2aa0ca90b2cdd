"""Experiments: metrics, batch runs, benchmarks and the paper's studies."""
