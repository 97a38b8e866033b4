"""The explorer engine of `make dse`: space files, knobs, rungs, workers, the store, Pareto fronts and the report."""
