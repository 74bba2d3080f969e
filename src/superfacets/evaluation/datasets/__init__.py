"""Readers of public data sets (the Princeton segmentation benchmark, labelled real scans)."""
