"""The scene's Origin rule (app.scene.common.origin): which websocket handshakes may open a session.

The live handshake against the running server is in tests/test_hostile.py; here the rule itself,
case by case, and the guard that refuses to start a scene without the check.
"""

from __future__ import annotations

import pytest

from app.scene.common.origin import OriginPolicy, normalise_origin, start_viser


@pytest.mark.parametrize(
    "bound, origin, host_header, allowed",
    [
        ("127.0.0.1", None, "127.0.0.1:8080", True),  # no Origin: not a browser
        ("127.0.0.1", "http://127.0.0.1:8080", "127.0.0.1:8080", True),
        ("127.0.0.1", "http://localhost:8080", "127.0.0.1:8080", True),  # 127.0.0.1 vs localhost
        ("127.0.0.1", "http://[::1]:8080", "[::1]:8080", True),
        ("127.0.0.1", "http://127.0.0.2:8080", "127.0.0.1:8080", True),  # all of 127/8 is loopback
        ("127.0.0.1", "https://example.org", "127.0.0.1:8080", True),  # --allow-origin
        ("127.0.0.1", "HTTPS://EXAMPLE.ORG:443", "127.0.0.1:8080", True),  # same origin, other spelling
        ("127.0.0.1", "http://example.org", "127.0.0.1:8080", False),  # allowed with https only
        ("127.0.0.1", "http://evil.example", "127.0.0.1:8080", False),
        ("127.0.0.1", "http://evil.example:8080", "evil.example:8080", False),  # DNS rebinding
        ("127.0.0.1", "http://localhost:9999", "localhost:8080", False),  # another local page
        ("127.0.0.1", "http://localhost:9090", "localhost:9090", True),  # port mapping 9090 -> 8080
        ("0.0.0.0", "http://192.168.1.5:8080", "192.168.1.5:8080", True),  # the LAN address it was loaded from
        ("0.0.0.0", "http://192.168.1.99:8080", "192.168.1.5:8080", False),  # another machine's page
        ("0.0.0.0", "http://192.168.1.99:8080", "localhost:8080", False),
        ("192.168.1.5", "http://192.168.1.5:8080", "192.168.1.5:8080", True),
        ("127.0.0.1", "null", "127.0.0.1:8080", False),  # sandboxed iframe, file://
        ("127.0.0.1", "file://", "127.0.0.1:8080", False),
        ("127.0.0.1", "http://localhost:8080/path", "localhost:8080", False),  # not an origin
        ("127.0.0.1", "http://localhost:notaport", "localhost:8080", False),
    ],
)
def test_origin_rule(bound, origin, host_header, allowed):
    policy = OriginPolicy(bound, ["https://example.org"], port=8080)
    assert policy.allows(origin, host_header) is allowed


def test_machine_name_is_the_scene_s_own():
    policy = OriginPolicy("0.0.0.0", port=8080)
    name = next(iter(policy.machine_names))
    assert policy.allows(f"http://{name}:8080", f"{name}:8080")
    assert not policy.allows(f"http://{name}.evil.example:8080", f"{name}.evil.example:8080")


@pytest.mark.parametrize(
    "text, expected",
    [
        ("https://Example.org/", "https://example.org"),
        ("http://example.org:80", "http://example.org"),
        ("http://10.0.0.5:8080", "http://10.0.0.5:8080"),
        ("http://[::1]:8080", "http://[::1]:8080"),
    ],
)
def test_normalise_origin(text, expected):
    assert normalise_origin(text) == expected


@pytest.mark.parametrize("text", ["example.org", "ftp://example.org", "http://example.org/app", "http://u:p@example.org", "http://x:99999"])
def test_allow_origin_rejects_what_is_not_an_origin(text):
    with pytest.raises(ValueError, match="not an origin"):
        normalise_origin(text)


def test_cli_option_checks_origins(capsys):
    from app.cli import main

    with pytest.raises(SystemExit) as e:
        main(["serve", "--allow-origin", "example.org"])
    assert e.value.code == 2
    assert "not an origin: 'example.org'" in capsys.readouterr().err


def test_scene_never_starts_without_the_check(monkeypatch):
    """If viser started its websocket server some other way, start_viser refuses (and stops it)."""
    import viser

    stopped = []

    class NoServe:
        def __init__(self, **kwargs):
            pass

        def stop(self):
            stopped.append(True)

    monkeypatch.setattr(viser, "ViserServer", NoServe)
    with pytest.raises(RuntimeError, match="Origin check of the scene could not be installed"):
        start_viser(OriginPolicy("127.0.0.1"), host="127.0.0.1", port=0)
    assert stopped == [True]


def test_stop_does_not_wait_for_a_connection_that_never_sent_a_request():
    """A browser's spare socket (a TCP connection that sends no request) is dropped when the scene
    stops. Was: ``websockets`` waited up to 10 s for its handshake; viser's stop() gave up after
    6 s with the connection still open, so a scene that two tabs had opened took 6 s to stop."""
    import socket

    from browser_helpers import until

    from app.scene.common import origin
    from app.scene.server import start_scene

    scene = start_scene("127.0.0.1", 0, processes=False)
    with socket.create_connection(("127.0.0.1", scene.port), timeout=30) as idle:
        until(lambda: origin._WEBSOCKETS[scene.server].handlers, 30, "the scene to accept the connection (no request sent)")
        scene.stop()
        idle.setblocking(False)
        try:
            dropped = idle.recv(1) == b""  # end of stream: the server closed it
        except ConnectionResetError:
            dropped = True  # aborted
        except BlockingIOError:
            dropped = False  # still open, waiting for a request
        assert dropped, "the idle connection is still open after stop()"
