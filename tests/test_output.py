"""``--out`` respects what the path is (app.output, issue 52 item 3).

A regular file is replaced whole or not at all; a symbolic link is followed and its target
replaced (the link stays); a character device, FIFO or socket is written in place (never
replaced by a regular file); a temporary file left by a writer killed with SIGKILL is removed
by the next run, and only such files. Device nodes are made in the test's folder (``mknod``,
as root), never the system's, so that a regression cannot replace ``/dev/null``.
"""

from __future__ import annotations

import fcntl
import os
import signal
import socket
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from test_cli_edges import ENV, ROOT, bodies_csv, no_temporary_files, run

from app.output import Output, remove_stale_temporaries


def parts(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".part"))


def wait_for(condition, what: str, deadline: float = 60.0) -> None:
    """Wait until ``condition()`` holds (a state, not a time), failing after ``deadline`` seconds."""
    end = time.monotonic() + deadline
    while not condition():
        assert time.monotonic() < end, f"timed out waiting for {what}"
        time.sleep(0.02)


def pairs_of(src: Path, tmp: Path) -> bytes:
    """The pairs file of ``contacts src`` written to a regular file (the reference)."""
    ref = tmp / "reference.csv"
    r = run("contacts", str(src), "--out", str(ref), "--quiet")
    assert r.returncode == 0, r.stderr.decode()
    return ref.read_bytes()


# ----------------------------------------------------------------------------- symbolic links
def test_a_symlink_is_followed_and_its_target_replaced_atomically(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    target = data / "pairs.csv"
    target.write_text("old pairs\n")
    os.chmod(target, 0o640)
    link = tmp_path / "latest.csv"
    link.symlink_to(os.path.relpath(target, tmp_path))
    src = bodies_csv(tmp_path / "b.csv")
    r = run("contacts", str(src), "--out", str(link), "--quiet")
    assert r.returncode == 0, r.stderr.decode()
    assert link.is_symlink() and link.resolve() == target
    assert target.read_bytes() == pairs_of(src, tmp_path) and target.read_text().startswith("i,j,relation")
    assert stat.S_IMODE(target.stat().st_mode) == 0o640  # the target's permissions kept
    # a failed run leaves the target as it was, and no temporary file beside the link or the target
    target.write_text("old pairs\n")
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z,a,b,c,qw,qx,qy,qz\n1,2,3,1,1,1,1,0,0,zero\n")
    r = run("contacts", str(bad), "--out", str(link))
    assert r.returncode == 2 and "line 2" in r.stderr.decode()
    assert target.read_text() == "old pairs\n" and link.is_symlink()
    no_temporary_files(tmp_path)
    no_temporary_files(data)


def test_a_dangling_symlink_creates_its_target_and_a_loop_is_refused(tmp_path):
    link = tmp_path / "out.csv"
    link.symlink_to("made/pairs.csv")
    with pytest.raises(ValueError, match=r"the folder .*made does not exist \(the target of the link"):
        Output(link)
    (tmp_path / "made").mkdir()
    with Output(link) as f:
        f.write("done\n")
    assert link.is_symlink() and (tmp_path / "made" / "pairs.csv").read_text() == "done\n"
    (tmp_path / "a").symlink_to("b")
    (tmp_path / "b").symlink_to("a")
    with pytest.raises(ValueError, match=r"a loop of symbolic links"):
        Output(tmp_path / "a")


# ----------------------------------------------------------------------------- devices, FIFOs, sockets
def test_a_fifo_is_written_in_place_for_its_reader(tmp_path):
    """The reader of a FIFO gets every byte and the FIFO stays a FIFO (it was replaced by a file)."""
    src = bodies_csv(tmp_path / "b.csv")
    want = pairs_of(src, tmp_path)
    fifo = tmp_path / "pairs.fifo"
    os.mkfifo(fifo)
    p = subprocess.Popen([sys.executable, "-m", "app", "contacts", str(src), "--out", str(fifo), "--quiet"],
                         cwd=ROOT, env=ENV, stderr=subprocess.PIPE)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    reader.join(timeout=120)
    if reader.is_alive():  # the writer never opened the FIFO: unblock the reader, then fail
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        reader.join(timeout=10)
    err = p.communicate(timeout=120)[1].decode()
    assert p.returncode == 0, err
    assert got == [want] and len(want) > 100
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    no_temporary_files(tmp_path)


def test_a_fifo_without_a_reader_is_waited_for_and_said(tmp_path, capsys):
    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    done: list[Output] = []
    writer = threading.Thread(target=lambda: done.append(Output(fifo)), daemon=True)
    writer.start()
    said: list[str] = []
    wait_for(lambda: said.append(capsys.readouterr().err) or "waiting for a reader of the FIFO" in "".join(said), "the message")
    assert not done  # still waiting
    with open(fifo, "rb") as reader:  # opening the read end releases the writer
        writer.join(timeout=60)
        assert done, "the writer did not open the FIFO once a reader came"
        with done[0] as f:
            f.write("through the pipe\n")
        assert reader.read() == b"through the pipe\n"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and os.listdir(tmp_path) == ["f"]


@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_a_character_device_is_written_in_place_not_replaced(tmp_path):
    null = tmp_path / "null"
    os.mknod(null, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # a /dev/null of the test's own
    before = os.lstat(null)
    src = bodies_csv(tmp_path / "b.csv")
    r = run("contacts", str(src), "--out", str(null), "--quiet")
    assert r.returncode == 0, r.stderr.decode()
    after = os.lstat(null)
    assert stat.S_ISCHR(after.st_mode) and (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)
    no_temporary_files(tmp_path)
    disk = tmp_path / "disk"
    os.mknod(disk, stat.S_IFBLK | 0o600, os.makedev(7, 0))
    with pytest.raises(ValueError, match=r"is a block device \(a disk\): give a file name"):
        Output(disk)
    assert stat.S_ISBLK(os.lstat(disk).st_mode)


def test_dev_null_as_another_user_is_written_not_refused():
    """The common ``--out /dev/null`` idiom (as root this test would not touch it: see the one above)."""
    if os.geteuid() == 0:
        pytest.skip("as root a regression would replace the system's /dev/null; the mknod test covers root")
    with Output("/dev/null") as f:
        f.write("discarded\n")
    assert stat.S_ISCHR(os.lstat("/dev/null").st_mode)


def test_a_link_to_this_process_stdout_writes_to_the_pipe(tmp_path):
    """``--out /dev/stdout`` (here a link of the test's own to /proc/self/fd/1): the data on the pipe."""
    src = bodies_csv(tmp_path / "b.csv")
    want = pairs_of(src, tmp_path)
    stdout = tmp_path / "stdout"
    stdout.symlink_to("/proc/self/fd/1")
    r = run("contacts", str(src), "--out", str(stdout), "--quiet")
    assert r.returncode == 0, r.stderr.decode()
    assert r.stdout == want
    assert stdout.is_symlink() and os.readlink(stdout) == "/proc/self/fd/1"


def test_a_listening_unix_socket_receives_the_data(tmp_path):
    path = tmp_path / "s.sock"
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(str(path))
    server.listen(1)
    got: list[bytes] = []

    def serve() -> None:
        conn, _ = server.accept()
        with conn:
            chunks = []
            while chunk := conn.recv(65536):
                chunks.append(chunk)
            got.append(b"".join(chunks))

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    with Output(path, binary=True) as f:
        f.write(b"over the socket")
    t.join(timeout=60)
    server.close()
    assert got == [b"over the socket"] and stat.S_ISSOCK(os.lstat(path).st_mode)
    with pytest.raises(ValueError, match=r"cannot write to this socket: Connection refused"):
        Output(path)  # no one listens any more


# ----------------------------------------------------------------------------- stale temporary files
def test_a_temporary_file_left_by_sigkill_is_removed_by_the_next_run(tmp_path):
    src = bodies_csv(tmp_path / "b.csv")
    out = tmp_path / "pairs.csv"
    # reading the bodies from stdin, the run waits after making its temporary file: killed there
    p = subprocess.Popen([sys.executable, "-m", "app", "contacts", "-", "--out", str(out)], cwd=ROOT, env=ENV,
                         stdin=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        wait_for(lambda: parts(tmp_path), "the run's temporary file")
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait(timeout=60)
        p.stdin.close()
    left = parts(tmp_path)
    assert len(left) == 1 and left[0].startswith(f".pairs.csv.{p.pid}.") and not out.exists()
    r = run("contacts", str(src), "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr.decode()
    assert parts(tmp_path) == [] and out.read_bytes() == pairs_of(src, tmp_path)


def dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_only_provably_stale_temporary_files_are_removed(tmp_path):
    target = tmp_path / "pairs.csv"
    gone = dead_pid()
    stale = tmp_path / f".pairs.csv.{gone}.abcd1234.part"
    alive = tmp_path / f".pairs.csv.{os.getpid()}.abcd1234.part"  # a writer that runs (this process)
    locked = tmp_path / f".pairs.csv.{gone}.locked00.part"  # its lock held: a writer in another pid namespace
    other = tmp_path / f".other.csv.{gone}.abcd1234.part"  # another output's
    nested = tmp_path / f".pairs.csv.1.{gone}.abcd1234.part"  # the output "pairs.csv.1"'s
    odd = tmp_path / f".pairs.csv.{gone}.part"  # not our pattern
    for p in (stale, alive, locked, other, nested, odd):
        p.write_text("partial")
    link = tmp_path / f".pairs.csv.{gone}.link0000.part"
    link.symlink_to(target)
    holder = os.open(locked, os.O_RDONLY)
    try:
        fcntl.flock(holder, fcntl.LOCK_EX)
        assert remove_stale_temporaries(target) == [stale]
    finally:
        os.close(holder)
    assert not stale.exists() and all(p.exists() for p in (alive, other, nested, odd)) and link.is_symlink()
    assert remove_stale_temporaries(target) == [locked]  # its lock released, its pid gone
    with Output(target) as f:  # the same clean-up runs before every write, and leaves its own file alone
        f.write("x")
    assert target.read_text() == "x" and alive.exists()
