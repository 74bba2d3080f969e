

def test_the_hierarchys_crease_defaults_are_the_methods():
    """The hierarchy (below the method) keeps the method's alpha and eta_convex."""
    from superfacets import DEFAULTS
    from superfacets.graph.hierarchy import ALPHA, ETA_CONVEX

    assert (ALPHA, ETA_CONVEX) == (DEFAULTS.alpha, DEFAULTS.eta_convex)
