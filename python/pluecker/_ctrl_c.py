"""Ctrl-C in the ``pluecker`` command: the process ends, status 130 with its one line, at most
:data:`GRACE` seconds after SIGINT, also while Python cannot act on the signal, and also when a library
turned the ``KeyboardInterrupt`` into an error of its own (:func:`caused_by_ctrl_c`).

Python runs its SIGINT handler on the main thread between bytecodes, so a library call that holds the
GIL for seconds (pycolmap reading or writing a model, numpy sorting millions of rows on the main
thread) holds Ctrl-C up as long. :func:`arm` makes Python's C-level handler also write the signal's
number to a pipe (``signal.set_wakeup_fd``) read by a native thread that never takes the GIL
(``_core._ExitDeadline``); unless the command :meth:`Deadline.stand_down` first (it caught the
``KeyboardInterrupt`` in time and prints the line itself), that thread prints the line and ends the
process with ``_exit``: no ``finally`` block runs then. What the command was writing is removed first:
the temporary folders and files of its outputs and the parent folders made for them, registered with
:func:`removed_on_forced_exit` (``pluecker._paths`` does it for every output). Only the program arms
the deadline (``pluecker.cli.run``), never a library call; without it the registrations do nothing.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from pathlib import Path
from typing import Iterator

from . import _core

#: Seconds from SIGINT to the end of the process when Python has not answered it by then.
GRACE = 0.05


class Deadline:
    """An armed deadline (:func:`arm`)."""

    def __init__(self, native, write: int, previous: int) -> None:
        self._native = native
        self._write = write
        self._previous = previous

    def stand_down(self) -> None:
        """The command answers Ctrl-C itself from now on."""
        self._native.stand_down()

    def close(self) -> None:
        """Stands down, gives the wakeup fd back and ends the native thread (the pipe's end)."""
        global _armed
        _armed = None
        self._native.stand_down()
        signal.set_wakeup_fd(self._previous)
        os.close(self._write)


def arm(command: str) -> Deadline | None:
    """The deadline of ``pluecker COMMAND``; ``None`` where it cannot be armed (not POSIX, not the main
    thread)."""
    native = getattr(_core, "_ExitDeadline", None)
    if native is None or threading.current_thread() is not threading.main_thread():
        return None
    read, write = os.pipe()
    os.set_blocking(write, False)  # as set_wakeup_fd requires
    previous = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    try:
        # From here the native thread owns ``read``.
        guard = native(read, GRACE, f"pluecker {command}: interrupted\n", 130)
    except BaseException:
        signal.set_wakeup_fd(previous)
        os.close(write)
        raise
    global _armed
    _armed = Deadline(guard, write, previous)
    return _armed


#: The deadline armed in this process, if any.
_armed: Deadline | None = None


@contextlib.contextmanager
def removed_on_forced_exit(path: str | os.PathLike, *, whole: bool = True) -> Iterator[None]:
    """Within the block, a forced exit of the armed deadline removes ``path`` first: whole (a temporary
    folder or file of an unfinished output) or, with ``whole=False``, only if empty (a parent folder
    made for an output). Register before creating the path: a path that is not there is skipped."""
    deadline = _armed
    if deadline is None:
        yield
        return
    key = str(Path(path).absolute())
    deadline._native.remove_on_exit(key, whole)
    try:
        yield
    finally:
        deadline._native.keep(key)


def caused_by_ctrl_c(error: BaseException) -> bool:
    """Whether ``error`` is a ``KeyboardInterrupt`` or was raised while handling one (its chain of
    ``__cause__`` / ``__context__`` holds one): pycolmap, interrupted while it loads its C++ module,
    raises ``RuntimeError`` from the ``ImportError`` that Python made of the ``KeyboardInterrupt``."""
    seen: set[int] = set()
    link: BaseException | None = error
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return True
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return False
