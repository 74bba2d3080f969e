"""The superfacet graph (adjacency of the superfacets) and its hierarchy of coarser levels."""
