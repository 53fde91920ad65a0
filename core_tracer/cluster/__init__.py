"""Studies and optimisations on a Dask cluster: self-contained render tasks (``cells``), their
results kept by content (``cache``), and the client that runs them on a scheduler or on a local
cluster (``engine``). Dask (``distributed``) is imported only here, and only when used."""
