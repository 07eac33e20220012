"""The applications on top of :mod:`core`; nothing starts at import.

The viser scene (:mod:`app.scene`), the HTTP API (:mod:`app.api`), the worker processes both use
(:mod:`app.workers`), headless screenshots (:mod:`app.screenshot`), the scene in a notebook
(:mod:`app.notebook`), many bodies from files (:mod:`app.bodyfiles`, :mod:`app.bodies_cli`) and
the command line (``python -m app``, :mod:`app.cli`).
"""
