"""The one way motion-envs writes files: atomically, with the usual permissions.

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

This module is the bottom of the layer order: it imports only the standard library.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

__all__ = [
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "current_umask",
    "save_figure",
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
