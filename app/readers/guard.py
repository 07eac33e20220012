"""Checks the readers make before they parse or allocate (issue 52: hostile files).

A file's own claims (a count in a header, a shape, a size in an archive's directory) are checked
against the file's size before any array is made, and bytes that are no text (a gzip stream,
UTF-16, NUL bytes) are refused before a text parser sees them; every refusal is one line naming
the file. The format-specific checks live in each reader; these are the shared ones.
"""

from __future__ import annotations

import re

__all__ = ["GZIP_MAGIC", "refuse_non_text", "clip", "one_line"]

GZIP_MAGIC = b"\x1f\x8b"
"""The first bytes of a gzip stream."""


def refuse_non_text(head: bytes, name: str, what: str = "text table") -> None:
    r"""Refuse a text format's file whose first bytes are no UTF-8 text (one line saying what they are).

    Args:
        head: the file's first bytes (512 are plenty).
        name: the file's name, for the message.
        what: what the file should be, for the message ("text table", "LAMMPS dump", ...).

    Raises:
        ValueError: a gzip-compressed file, UTF-16 or UTF-32 text, NUL bytes.

    Examples:
        >>> refuse_non_text(b"x,y,a,b,angle\n", "ok.csv")
        >>> refuse_non_text(b"\xff\xfex\x00", "w.csv")
        Traceback (most recent call last):
        ...
        ValueError: w.csv: UTF-16 text (a byte order mark FF FE): save it as UTF-8
    """
    if head.startswith(GZIP_MAGIC):
        raise ValueError(f"{name}: a gzip-compressed file: decompress it first (gunzip), then read the {what}")
    for bom, encoding in ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"), (b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16")):
        if head.startswith(bom):
            raise ValueError(f"{name}: {encoding} text (a byte order mark {bom.hex(' ').upper()}): save it as UTF-8")
    if b"\0" in head:
        line = head[: head.index(b"\0")].count(b"\n") + 1
        raise ValueError(f"{name}: line {line} holds NUL bytes: binary data, not a {what}")


def clip(text: str, limit: int = 160) -> str:
    """``text`` cut in the middle to at most about ``limit`` characters (values quoted in messages).

    Examples:
        >>> clip("9" * 1000, 20)
        '999999999 ... 9999999999 (1,000 characters)'
    """
    if len(text) <= limit:
        return text
    half = limit // 2
    return f"{text[: half - 1]} ... {text[-half:]} ({len(text):,} characters)"


def one_line(error: BaseException | str, limit: int = 160) -> str:
    r"""A library's message as one short line (its whitespace and newlines folded, cut in the middle).

    Object reprs lose their memory address (``<ast.Name object>``): the same file gives the same message.

    Examples:
        >>> one_line(ValueError("Couldn't deserialize thrift: Invalid data\n"))
        "Couldn't deserialize thrift: Invalid data"
    """
    return clip(re.sub(r" at 0x[0-9a-fA-F]+>", ">", " ".join(str(error).split())), limit)
