"""The one way motion-envs writes files (atomically) and reads user files (bounded).

Every file the project writes (results JSON/CSV, plots, model files, cohort configs)
goes through :func:`atomic_write`: the content is written to a *unique* temporary file
in the target folder (``.NAME.<16 random hex digits>.tmp``, created exclusively), flushed
and ``fsync``-ed, with the permissions a plain ``open(path, "w")`` would give (``0o666 &
~umask``, i.e. 0644 under the default umask 022), then renamed over the target with
``os.replace``. Hence:

* an interrupted write (Ctrl-C, a killed process, a full disk) leaves the previous file
  complete and no partial target; the temporary file is removed whenever Python gets to
  run (Ctrl-C at any moment, an exception); only a process killed outright (SIGKILL, a
  power cut) can leave a ``.NAME.*.tmp`` behind;
* two processes writing the same path both finish and the target holds one of the two
  complete versions (the last rename wins); neither sees a half-written file.

Reading a file a user names (a model file, a config) goes through
:func:`read_regular_file`: only a regular file is read (a folder, a FIFO, ``/dev/zero`` or
another device is refused before any byte is read, so nothing blocks or fills memory), and
at most ``max_bytes`` bytes, counted while reading rather than trusted from ``st_size``.
:func:`strict_json_loads` parses JSON that a program wrote: a duplicate key, ``NaN`` /
``Infinity`` or nesting deeper than Python's recursion limit is an error, not a silent
choice. Both raise :class:`UserFileError` (a ``ValueError``) whose message names the file;
callers re-raise it as their own documented error type.

This module is the bottom of the layer order: it imports only the standard library.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import stat
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

__all__ = [
    "UserFileError",
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "current_umask",
    "read_regular_file",
    "save_figure",
    "strict_json_loads",
]


_O_BINARY = getattr(os, "O_BINARY", 0)  # Windows: no newline translation at the fd level


def current_umask() -> int:
    """The process's file-creation mask.

    Read from ``/proc/self/status`` where it exists (Linux), so the mask is never changed,
    not even briefly; elsewhere ``os.umask`` is set and restored.
    """
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(
    path: str | os.PathLike[str], write: Callable[[IO[Any]], object], binary: bool = False
) -> Path:
    """Create or replace ``path`` atomically with what ``write(fh)`` writes to ``fh``.

    ``fh`` is the open temporary file (text, UTF-8, ``\\n`` newlines, or binary with
    ``binary=True``). Parent folders are created. Returns the target path.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    # The temporary name is known before the file exists and the file is created inside
    # the ``try``: a Ctrl-C at any point (even right after the file appears) removes it.
    tmp = target.parent / f".{target.name}.{secrets.token_hex(8)}.tmp"
    try:
        # 0o666 minus the umask (applied by the kernel), as a plain open(path, "w") gives
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_BINARY, 0o666)
        mode = "wb" if binary else "w"
        kwargs: dict[str, Any] = {} if binary else {"encoding": "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **kwargs) as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return target


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`atomic_write`)."""
    return atomic_write(path, lambda fh: fh.write(text))


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_write`)."""
    return atomic_write(path, lambda fh: fh.write(data), binary=True)


def save_figure(fig: Any, path: str | os.PathLike[str], **savefig_kwargs: Any) -> Path:
    """Save a matplotlib figure to ``path`` atomically (``fig.savefig`` into the temp file).

    The format comes from the path's suffix (``.png`` by default); ``savefig_kwargs``
    (``dpi``, ...) are passed on. matplotlib is not imported here: any object with a
    ``savefig(file, format=...)`` method works.
    """
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    return atomic_write(path, lambda fh: fig.savefig(fh, format=fmt, **savefig_kwargs), binary=True)


class UserFileError(ValueError):
    """A file a user named cannot be read as asked; the message names the file."""


_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def read_regular_file(path: str | os.PathLike[str], *, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    Raises :class:`UserFileError` naming ``path`` when it does not exist, cannot be
    opened, is not a regular file (folder, FIFO, device, socket: checked on the open
    descriptor, which is opened non-blocking so that a FIFO without a writer does not
    block), or holds more than ``max_bytes`` bytes (counted while reading, so a file that
    grows or lies about its size is still bounded).
    """
    p = os.fspath(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | _O_BINARY
    try:
        fd = os.open(p, flags)
    except FileNotFoundError:
        raise UserFileError(f"{p} does not exist") from None
    except IsADirectoryError:
        raise UserFileError(f"{p} is a directory, not a file") from None
    except OSError as exc:
        raise UserFileError(f"{p} cannot be read: {exc.strerror or exc}") from None
    try:
        mode = os.fstat(fd).st_mode
        for test, kind in _KINDS:
            if test(mode):
                raise UserFileError(f"{p} is {kind}, not a regular file")
        chunks: list[bytes] = []
        size = 0
        while True:
            try:
                chunk = os.read(fd, min(1 << 20, max_bytes + 1 - size))
            except OSError as exc:
                raise UserFileError(f"{p} cannot be read: {exc.strerror or exc}") from None
            if not chunk:
                return b"".join(chunks)
            size += len(chunk)
            if size > max_bytes:
                raise UserFileError(f"{p} is larger than {max_bytes} bytes")
            chunks.append(chunk)
    finally:
        os.close(fd)


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    doc: dict[str, Any] = {}
    for key, value in pairs:
        if key in doc:
            raise ValueError(f"duplicate key {key!r}")
        doc[key] = value
    return doc


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not allowed")


def strict_json_loads(text: str | bytes, where: str, **kwargs: Any) -> Any:
    """Parse JSON ``text``; :class:`UserFileError` naming ``where`` for anything odd.

    Refused: invalid JSON, a duplicate key in any object, ``NaN``/``Infinity``, nesting
    deeper than the interpreter's recursion limit. ``kwargs`` go to :func:`json.loads`
    (e.g. ``parse_float``; ``object_pairs_hook`` and ``parse_constant`` are this
    function's).
    """
    try:
        return json.loads(
            text,
            object_pairs_hook=_no_duplicates,
            parse_constant=kwargs.pop("parse_constant", _no_constant),
            **kwargs,
        )
    except json.JSONDecodeError as exc:
        raise UserFileError(
            f"{where} is corrupt or truncated: not valid JSON ({exc.msg} at line {exc.lineno})"
        ) from None
    except RecursionError:
        raise UserFileError(f"{where}: JSON nested deeper than the parser's limit") from None
    except UnicodeDecodeError:
        raise UserFileError(f"{where}: not UTF-8 text") from None
    except ValueError as exc:
        raise UserFileError(f"{where}: {exc}") from None
