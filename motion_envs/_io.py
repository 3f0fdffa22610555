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
:func:`check_regular_file` is the same check without the reading, for readers that take
a path (pandas, ezc3d, pybvh): the file is opened non-blocking, checked on the open
descriptor and its size bounded before the path is handed on.

Outputs follow one rule, :func:`check_output`: an existing target is replaced only when it
is a regular file (a folder only when it is a folder), never through a symbolic link, and
never when it is the same file as an input (``os.path.samefile``). :func:`atomic_write`
applies the first two to every file it writes and refuses to replace any file registered
with :func:`protected_inputs` (the command line registers its input files for the whole
run), so an output can never take the place of a FIFO, a device, a symbolic link's
target or an input. :func:`folder_lock` holds an exclusive, non-blocking ``flock`` on an
output folder for a run: a second process writing the same folder gets a one-line
:class:`UserFileError` (the lock is released when the process ends, whatever the end).
A write that fails (a full disk, ``EIO``) raises ``OSError`` naming the target.

This module is the bottom of the layer order: it imports only the standard library.
"""

from __future__ import annotations

import contextlib
import errno as _errno
import json
import os
import secrets
import stat
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "UserFileError",
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_output",
    "check_regular_file",
    "current_umask",
    "folder_lock",
    "protected_inputs",
    "read_regular_file",
    "read_regular_text",
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
    check_output(target)
    _refuse_protected(target)
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
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not exc.filename and exc.errno is not None:
            # a full disk or an I/O error inside write(): the line names the file
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from None
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


def _open_regular(p: str) -> tuple[int, int]:
    """A read-only descriptor of the regular file ``p`` (opened non-blocking) and its size."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | _O_BINARY
    try:
        fd = os.open(p, flags)
    except FileNotFoundError:
        raise UserFileError(f"{p} does not exist") from None
    except IsADirectoryError:
        raise UserFileError(f"{p} is a directory, not a file") from None
    except OSError as exc:
        raise UserFileError(f"cannot read {p}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        for test, kind in _KINDS:
            if test(st.st_mode):
                raise UserFileError(f"{p} is {kind}, not a regular file")
    except BaseException:
        os.close(fd)
        raise
    return fd, st.st_size


def _too_large(p: str, max_bytes: int) -> UserFileError:
    return UserFileError(f"{p} is larger than {max_bytes} bytes")


def check_regular_file(path: str | os.PathLike[str], *, max_bytes: int) -> Path:
    """``path`` when it is a regular file of at most ``max_bytes`` bytes (by its size).

    The check of :func:`read_regular_file` without reading, for readers that need a path
    (the file is opened non-blocking and checked on the descriptor, so a FIFO, a device or
    a symbolic link to one is refused before any reader can block on it).
    """
    p = os.fspath(path)
    fd, size = _open_regular(p)
    os.close(fd)
    if size > max_bytes:
        raise _too_large(p, max_bytes)
    return Path(p)


def read_regular_file(path: str | os.PathLike[str], *, max_bytes: int, head: bool = False) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them.

    Raises :class:`UserFileError` naming ``path`` when it does not exist, cannot be
    opened, is not a regular file (folder, FIFO, device, socket: checked on the open
    descriptor, which is opened non-blocking so that a FIFO without a writer does not
    block), or holds more than ``max_bytes`` bytes (counted while reading, so a file that
    grows or lies about its size is still bounded). With ``head=True`` a longer file is
    not an error: its first ``max_bytes`` bytes are returned (a header line's check).
    """
    p = os.fspath(path)
    fd, _ = _open_regular(p)
    try:
        chunks: list[bytes] = []
        size = 0
        while True:
            try:
                chunk = os.read(fd, min(1 << 20, max_bytes + 1 - size))
            except OSError as exc:
                raise UserFileError(f"cannot read {p}: {exc.strerror or exc}") from None
            if not chunk:
                return b"".join(chunks)
            size += len(chunk)
            if size > max_bytes:
                if head:
                    chunks.append(chunk[: len(chunk) - (size - max_bytes)])
                    return b"".join(chunks)
                raise _too_large(p, max_bytes)
            chunks.append(chunk)
    finally:
        os.close(fd)


def read_regular_text(
    path: str | os.PathLike[str], *, max_bytes: int, encoding: str = "utf-8"
) -> str:
    """:func:`read_regular_file` decoded (``UserFileError`` naming the file if it is not
    ``encoding`` text)."""
    data = read_regular_file(path, max_bytes=max_bytes)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise UserFileError(
            f"{os.fspath(path)}: not {encoding} text (byte {exc.start} cannot be decoded)"
        ) from None


def _kind(mode: int) -> str:
    if stat.S_ISREG(mode):
        return "a regular file"
    return next((kind for test, kind in _KINDS if test(mode)), "not a regular file")


def check_output(
    path: str | os.PathLike[str],
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
    folder: bool = False,
) -> Path:
    """``path`` when a run may write it (THE output rule; :class:`UserFileError` if not).

    Refused: a symbolic link (whatever it points to), an existing ``path`` that is not a
    regular file (``folder=True``: not a folder), and ``path`` being the same file or
    folder as one of ``inputs`` (``os.path.samefile``). A path that does not exist yet
    is fine.
    """
    p = os.fspath(path)
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        return Path(p)
    except OSError as exc:
        raise UserFileError(f"{p} cannot be written: {exc.strerror or exc}") from None
    if stat.S_ISLNK(st.st_mode):
        raise UserFileError(
            f"{p} is a symbolic link; refusing to write through it (give the real path)"
        )
    if folder and not stat.S_ISDIR(st.st_mode):
        raise UserFileError(f"{p} is {_kind(st.st_mode)}, not a folder")
    if not folder and not stat.S_ISREG(st.st_mode):
        raise UserFileError(
            f"{p} is {_kind(st.st_mode)}, not a regular file; refusing to replace it"
        )
    for source in inputs:
        with contextlib.suppress(OSError):
            if os.path.samefile(p, source):
                raise UserFileError(
                    f"{p} is the input {os.fspath(source)}; refusing to overwrite an input"
                )
    return Path(p)


#: ``(st_dev, st_ino)`` of the files registered by :func:`protected_inputs` -> their name.
_PROTECTED: dict[tuple[int, int], str] = {}


@contextlib.contextmanager
def protected_inputs(paths: Iterable[str | os.PathLike[str]]) -> Iterator[None]:
    """While the block runs, :func:`atomic_write` refuses to replace any of ``paths`` (the
    files themselves, whatever name reaches them). Paths that do not exist are ignored."""
    added: list[tuple[int, int]] = []
    for path in paths:
        try:
            st = os.stat(path)
        except (OSError, ValueError):
            continue
        key = (st.st_dev, st.st_ino)
        if key not in _PROTECTED:
            _PROTECTED[key] = os.fspath(path)
            added.append(key)
    try:
        yield
    finally:
        for key in added:
            _PROTECTED.pop(key, None)


def _refuse_protected(target: Path) -> None:
    if not _PROTECTED:
        return
    try:
        st = os.stat(target)
    except OSError:
        return
    name = _PROTECTED.get((st.st_dev, st.st_ino))
    if name is not None:
        raise UserFileError(f"{target} is the input {name}; refusing to overwrite an input")


#: Folders this process holds a lock on: real path -> (descriptor, depth).
_LOCKS: dict[str, tuple[int, int]] = {}


@contextlib.contextmanager
def folder_lock(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Hold an exclusive lock on the output folder ``path`` while the block runs.

    The folder is created if absent (and removed again at the end if this call created it
    and it is still empty). The lock is ``flock(LOCK_EX | LOCK_NB)`` on the folder's own
    descriptor: nothing is written into the folder, the lock ends with the process however
    it ends, and a second process gets :class:`UserFileError` at once ("... is being
    written by another process") instead of mixing its files with the first's. Nested
    calls on one folder in one process share the lock. Without ``fcntl`` (Windows) the
    folder is created but not locked.
    """
    folder = Path(path)
    check_output(folder, folder=True)
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    key = os.path.realpath(folder)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        fcntl = None  # type: ignore[assignment]
    held = _LOCKS.get(key)
    fd = -1
    if held is not None:
        _LOCKS[key] = (held[0], held[1] + 1)
    elif fcntl is not None:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (_errno.EWOULDBLOCK, _errno.EAGAIN, _errno.EACCES):
                raise UserFileError(
                    f"{folder} is being written by another process; wait for it to end or "
                    "choose another folder"
                ) from None
            raise
        _LOCKS[key] = (fd, 1)
    try:
        yield folder
    finally:
        held = _LOCKS.get(key)
        if held is not None:
            if held[1] > 1:
                _LOCKS[key] = (held[0], held[1] - 1)
            else:
                del _LOCKS[key]
                os.close(held[0])  # closing the descriptor releases the flock
        if created:
            with contextlib.suppress(OSError):
                folder.rmdir()  # only when still empty


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
