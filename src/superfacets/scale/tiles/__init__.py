"""One input in tiles with halos (``segment_tiled``, ``superfacets segment --tiles``).

:mod:`.layout` cuts the input's box into tiles; :mod:`.buckets` reads the input once,
into one file per tile; :mod:`.phases` is what each tile's task does (the start on a
sample, the refine round, the labels, the connectivity); :mod:`.graphs` keeps each tile's
element graph for the later phases, and :mod:`.held` holds a tile in its worker's memory
between them; :mod:`.merges` merges the stitched superpoints to the
count; :mod:`.run` drives it all on :mod:`superfacets.scale.runner.engine` (this process
or Dask), in a work folder (:mod:`.workdir`). The design record: ``docs/notes/tiles.md``.
"""
