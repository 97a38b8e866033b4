"""Measurement studies beside the explorer: make precision, fidelity, bench-caches, and the summaries of make bench and run."""
