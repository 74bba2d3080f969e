"""Baselines the paper compares with (section 5): normalized cuts and VSA.

Shlafman et al.'s weighting is not a separate method: it is the paper's
k-means with :func:`superfacets.method.weights.shlafman_weights`
(``superfacets(mesh, weighting="shlafman")``).
"""

from .ncuts import NcutEmbedding, ncut_embedding, normalized_cuts
from .vsa import VSAResult, variational_shape_approximation, vsa

__all__ = ["NcutEmbedding", "VSAResult", "ncut_embedding", "normalized_cuts",
           "variational_shape_approximation", "vsa"]
