"""Scale-out: spotkin's batch kernels over chunked Dask arrays (``dask_calls``, ``dask_graph``,
``dask_kernel``; the public :mod:`spotkin.dask`) and over datasets on disk (``batch_operations``,
``batch_data``, ``batch_run``: the ``spotkin batch`` command). Dask and Zarr are imported only when used."""
