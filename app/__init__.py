"""The applications on top of :mod:`core`.

The viser scene (:mod:`app.scene`), the HTTP API (:mod:`app.api`), headless screenshots
(:mod:`app.screenshot`) and the command line (``python -m app``, :mod:`app.cli`). Nothing
starts at import.
"""
