"""Scale: a build's heavy stages on Dask."""
