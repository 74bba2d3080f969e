"""The method, stage by stage: parameters, weights, initialization, expansions,
classification, passes, coarse-to-fine, content-sensitive sizes, split-and-merge,
clean-up, connectivity, labels; :mod:`~superfacets.method.stages` and
:mod:`~superfacets.method.pipeline` run them in order."""
