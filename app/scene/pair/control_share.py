"""Share, keep and export: a link to this view, the configuration as a file, the analysis as files.

* "Link to this view": a ``/c/<configuration>/`` link (:mod:`app.scene.common.links`) with a copy button;
  opening it starts a tab on exactly what this tab shows.
* "Download configuration (JSON)" / "Open a configuration (JSON)": the :class:`SceneConfig` of
  this view as a file (``--config`` reads the same file), and back; an opened file is user
  input, read like a link (a typed motion in it is read and analysed in worker processes).
* "Download analysis (JSON)" / "(CSV)": the exact analysis (:mod:`app.scene.pair.export`).

Files go to the tab that clicked (viser's file download).
"""

from __future__ import annotations

import html
import json
from typing import TYPE_CHECKING, Any

import viser

from ..common.links import link_path
from ..common.wire import too_large
from .export import analysis_csv, analysis_json, dumps
from .panels import copy_button

if TYPE_CHECKING:
    from .session_view import SessionView

__all__ = ["ShareControl", "MAX_UPLOAD_BYTES"]

MAX_UPLOAD_BYTES = 256 * 1024
"""Largest configuration file accepted (a motion typed at the longest expressions fits)."""


class ShareControl:
    """Callbacks of the "Share and keep" folder of one session."""

    def __init__(self, session: SessionView) -> None:
        self.s = session
        ui = session.ui.share
        ui.link.on_click(lambda ev: self.on_link())
        ui.download.on_click(lambda ev: self.download("scene.json", dumps(self.s.snapshot().to_dict()), ev.client))
        ui.upload.on_upload(lambda ev: self.on_upload(ev.target.value))
        if session.uploads is not None:  # a larger file is refused before the server keeps it
            session.uploads.limit(ui.upload, MAX_UPLOAD_BYTES, lambda r: self.s.field_error("config", r.message()))
        ui.analysis_json.on_click(lambda ev: self.on_analysis("json", ev.client))
        ui.analysis_csv.on_click(lambda ev: self.on_analysis("csv", ev.client))

    def on_link(self) -> None:
        """Show a link that opens a new tab on this view, with a button copying its address."""
        # relative to the tab's page /s/<id>/ (or / in presenter mode): also right behind a proxy
        # that serves the scene under a path of its own (a remote notebook's /proxy/PORT/)
        path = "../.." + link_path(self.s.snapshot())
        share = self.s.ui.share
        share.link_html.content = (
            f'<div style="font-size:12px"><a href="{html.escape(path, quote=True)}" target="_blank">'
            f"Open this view in a new tab</a>{copy_button(path, 'copy link', url=True)}</div>"
        )
        share.link_html.visible = True

    def download(self, name: str, data: bytes, client: viser.ClientHandle | None) -> None:
        """Send a file to the tab that asked (or to every tab of a shared scene)."""
        target: Any = client if client is not None else self.s.target
        target.send_file_download(name, data, save_immediately=True)

    def on_upload(self, file: Any) -> None:
        """A configuration file was opened: check it and show it (errors next to the button)."""
        s = self.s
        try:
            if len(file.content) > MAX_UPLOAD_BYTES:
                raise ValueError(too_large(file.name, len(file.content), MAX_UPLOAD_BYTES))
            try:
                data = json.loads(file.content.decode("utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as e:
                raise ValueError(f"{file.name} is not a JSON configuration: {e}") from None
            if not isinstance(data, dict):
                raise ValueError(f"{file.name}: expected a JSON object (a scene configuration)")
        except ValueError as e:
            s.field_error("config", str(e))
            return
        with s.lock:
            s.state.errors.pop("config", None)
        s.load_untrusted(data)
        s.frame_camera()

    def on_analysis(self, kind: str, client: viser.ClientHandle | None) -> None:
        """Download the analysis of the motion shown (nothing to do without one)."""
        st = self.s.state
        if st.motion is None or st.analysis is None:
            return
        name = (st.motion.preset or "motion") + "-analysis"
        if kind == "json":
            self.download(f"{name}.json", dumps(analysis_json(st.motion, st.analysis)), client)
        else:
            self.download(f"{name}.csv", analysis_csv(st.motion, st.analysis).encode(), client)
