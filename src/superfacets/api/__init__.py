"""The public functions and their results: segment, superfacets, superpoints, the
content-adaptive level, scenes object by object."""
