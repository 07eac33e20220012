"""The scene server's tabs (app.scene.server): each connected tab has one session, closed when it leaves."""

from __future__ import annotations

import threading

import msgspec
import pytest
import viser
from browser_helpers import until
from viser import _messages
from websockets.sync.client import connect

from app.scene.pair.session import Session
from app.scene.server import SceneServer, start_scene

CAMERA = msgspec.msgpack.encode(_messages.ViewerCameraMessage(
    wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 5.0), fov=1.0, near=0.01, far=100.0, image_height=600, image_width=800,
    look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0)).as_serializable_dict())
"""A tab's first message: viser counts a client as connected once it has reported its camera."""


# the build's last step sends the camera and grid to a tab that is gone, by construction: viser says so
@pytest.mark.filterwarnings("ignore:Queued a .* on a closed connection:UserWarning")
def test_a_tab_that_leaves_while_its_session_is_built_leaves_no_session(monkeypatch):
    """viser runs a client's connect and disconnect callbacks on a thread pool, so a tab closed
    (or reloaded) while its session is being built is seen leaving first. Was: the session was
    registered afterwards and never closed; its analyses and timers ran on for a tab that was gone.
    Here the last step of the build waits until the server has seen the tab leave."""
    built: list[Session] = []
    left = threading.Event()
    real_frame, real_disconnect = Session.frame_camera, SceneServer._disconnect

    def disconnect(self: SceneServer, client: viser.ClientHandle) -> None:
        real_disconnect(self, client)
        left.set()

    def frame_after_the_tab_left(self: Session) -> None:  # the build's last step
        built.append(self)
        until(left.is_set, 60, "the server to see the tab leave")
        real_frame(self)

    monkeypatch.setattr(SceneServer, "_disconnect", disconnect)
    monkeypatch.setattr(Session, "frame_camera", frame_after_the_tab_left)
    scene = start_scene("127.0.0.1", 0, processes=False, prefetch=False)
    try:
        with connect(f"ws://127.0.0.1:{scene.port}/", subprotocols=[f"viser-v{viser.__version__}"], open_timeout=30) as tab:
            tab.send(CAMERA)
            until(lambda: built, 60, "the tab's session to be built")
        until(lambda: built[0].closed, 60, "the session of the tab that left to be closed")
        assert scene.sessions == {}
    finally:
        scene.stop()


def _connected_tab(scene: SceneServer):
    """A websocket client of ``scene`` that counts as a tab (it reported its camera), and its session.

    It reads no message: with no bound on its queue it still sees the server's answer when it closes
    (with websockets' default of 16 messages, a close waited its 10 s timeout behind a full queue).
    """
    tab = connect(f"ws://127.0.0.1:{scene.port}/", subprotocols=[f"viser-v{viser.__version__}"], open_timeout=30,
                  max_queue=None)
    tab.send(CAMERA)
    until(lambda: scene.sessions, 60, "the tab's session to be built")
    return tab, next(iter(scene.sessions.items()))


@pytest.mark.filterwarnings("ignore:Queued a .* on a closed connection:UserWarning")
def test_renew_gives_the_tab_a_new_session_on_the_link_and_closes_the_old():
    """``SceneServer.renew`` (HeadlessScene.open): the tab's one session is a new one on the link's
    configuration, read as user input (a bad link is the default with its message, as a new tab's)."""
    scene = start_scene("127.0.0.1", 0, processes=False, prefetch=False)
    try:
        tab, (cid, old) = _connected_tab(scene)
        with tab:
            new = scene.renew(cid, {"preset": None, "A": {"center": [0, 0, 0], "semi_axes": [1, 1, 1]},
                                    "B": {"center": [2, 0, 0], "semi_axes": [1, 1, 1]}})
            assert old.closed and not new.closed and scene.sessions == {cid: new}
            assert new.ready.wait(60) and new.state.relation == "tangent"
            bad = scene.renew(cid, {"preset": "no-such-preset"})
            assert new.closed and scene.sessions == {cid: bad}
            assert bad.ready.wait(60) and any("no-such-preset" in m for m in bad.state.errors.values())
            with pytest.raises(KeyError, match="no tab 12345"):
                scene.renew(12345, {"preset": None})
    finally:
        scene.stop()
    shared = start_scene("127.0.0.1", 0, processes=False, prefetch=False, shared=True)
    try:
        with pytest.raises(ValueError, match="presenter"):
            shared.renew(0, {"preset": None})
    finally:
        shared.stop()


@pytest.mark.filterwarnings("ignore:Queued a .* on a closed connection:UserWarning")
def test_a_tab_that_leaves_while_it_is_renewed_leaves_no_session(monkeypatch):
    """A tab that closes while ``renew`` builds its new session: that session is closed, none stays
    (as for a tab that leaves while its first session is built, above)."""
    left, armed = threading.Event(), threading.Event()
    built: list[Session] = []
    real_frame, real_disconnect = Session.frame_camera, SceneServer._disconnect

    def disconnect(self: SceneServer, client: viser.ClientHandle) -> None:
        real_disconnect(self, client)
        left.set()

    def frame_after_the_tab_left(self: Session) -> None:  # the renewal's last step closes the tab first
        if armed.is_set():
            built.append(self)
            tab.close()
            until(left.is_set, 60, "the server to see the tab leave")
        real_frame(self)

    monkeypatch.setattr(SceneServer, "_disconnect", disconnect)  # before the server registers its callbacks
    monkeypatch.setattr(Session, "frame_camera", frame_after_the_tab_left)
    scene = start_scene("127.0.0.1", 0, processes=False, prefetch=False)
    try:
        tab, (cid, old) = _connected_tab(scene)
        armed.set()
        new = scene.renew(cid, {"preset": None})
        assert built == [new] and old.closed and new.closed and scene.sessions == {}
    finally:
        scene.stop()
