"""Readers of public data sets (the Princeton segmentation benchmark)."""
