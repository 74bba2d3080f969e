"""Scale: one input in tiles with halos, and the engine that runs tiles, batches and
experiments in this process or on Dask."""
