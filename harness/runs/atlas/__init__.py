"""Atlases: the plane of sigma and a second parameter, every pixel run from several starts to its
attractors (on the batch kernel or through the FMU), in tiles, checkpointed, resumable, on Dask."""
