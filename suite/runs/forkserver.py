"""Imported once, by the fork server that forks the workers of gnibench's own Dask LocalCluster
(:func:`gnibench.suite.runs.executors._forked_workers`), never by gnibench itself: importing it
does the work of :func:`gnibench.suite.runs.pool.preload` (the modules of a cell, numba and its
CPU target), so each worker forked from that server starts with it done."""
from gnibench.suite.runs.pool import preload

preload()
