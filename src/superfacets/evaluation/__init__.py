"""Judging a result: the metrics, the method registry, the baselines, the benchmark and
labelled scans, reports of experiments."""
