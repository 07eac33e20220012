"""Repository-level pytest configuration: the Dask module's doctests need the optional extra."""

import importlib.util

# core/bodies/distributed.py imports dask at import time (it is only imported when Dask is used);
# without ``pip install -e ".[dask]"`` its doctest collection is skipped instead of failing
collect_ignore = [] if importlib.util.find_spec("distributed") else ["core/bodies/distributed.py"]
