"""Paths of the inputs and outputs of the command line and of the functions that write folders.

One wording for an input that is missing or of the wrong kind (:func:`folder_problem`), one check that
an output is not an input, inside an input folder, or a folder that holds one (:func:`output_conflict`,
symlinks, ``.`` and ``..`` resolved), one check that an output can be written before any work
(:func:`output_problem`, which makes nothing), and one way to write, so that an interrupted or failed
run leaves no new empty or partial output and never half of a replaced one: into a temporary sibling,
then renamed into place (:func:`staged`, :func:`write_text`).
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
from pathlib import Path
from typing import Iterable, Iterator, Mapping

from pluecker import _ctrl_c

#: Suffix of the temporary folders and files that :func:`staged` and :func:`write_text` write into.
PARTIAL = ".partial"


def folder_problem(path: str | os.PathLike) -> str | None:
    """Why ``path`` is not a folder to read (``"no such directory"``, ``"not a directory"``), or ``None``."""
    path = Path(path)
    if not path.exists():
        return "no such directory"
    if not path.is_dir():
        return "not a directory"
    return None


def require_folder(path: str | os.PathLike, what: str = "") -> Path:
    """``path`` as a ``Path`` when it is a folder; else ``FileNotFoundError`` or ``NotADirectoryError``
    with the message ``"{what}{path}: no such directory"`` (or ``not a directory``)."""
    path = Path(path)
    problem = folder_problem(path)
    if problem is not None:
        error = FileNotFoundError if problem == "no such directory" else NotADirectoryError
        raise error(f"{what}{path}: {problem}")
    return path


def _resolved(path: str | os.PathLike) -> Path:
    return Path(os.path.abspath(Path(path).expanduser().resolve()))


def _same(a: Path, b: Path) -> bool:
    """Whether two resolved paths name the same file (also through a hard link or a bind mount)."""
    if a == b:
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _within(inner: Path, outer: Path) -> bool:
    """Whether the resolved ``inner`` is ``outer`` or lies inside it."""
    return _same(inner, outer) or any(_same(parent, outer) for parent in inner.parents)


def output_conflict(out: str | os.PathLike, inputs: Mapping[str, str | os.PathLike | None],
                    replaced: Iterable[str] = ()) -> str | None:
    """Why writing ``out`` would touch an input, or ``None``. ``inputs`` maps how the user named each
    input (``"INPUT"``, ``"--colmap"``) to its path (``None``: not given). Refused: ``out`` is an input;
    ``out`` lies inside an input folder; or one of the entries of ``out`` that the run replaces whole
    (``replaced``, names relative to ``out``; ``out`` itself when empty) is an input or holds one. Paths
    are compared resolved: symlinks, ``.`` and ``..`` do not hide an input."""
    target = _resolved(out)
    whole = [_resolved(Path(out) / name) for name in replaced] or [target]
    for name, given in inputs.items():
        if given is None:
            continue
        source = _resolved(given)
        if _same(target, source):
            return f"{out} is the input {name} {given}"
        if source.is_dir() and _within(target, source):
            return f"{out} is inside the input {name} {given}"
        for entry in whole:
            if _within(source, entry):
                return f"writing {entry if entry != target else out} would replace the input {name} {given}"
    return None


def output_problem(out: str | os.PathLike, *, folder: bool = True) -> str | None:
    """Why the output ``out`` (a folder, or a file with ``folder=False``) cannot be written, or ``None``,
    checked before any work and without making anything: an existing ``out`` of the wrong kind, or a
    nearest existing ancestor that is not a writable folder."""
    out = Path(out)
    if out.exists():
        if folder and not out.is_dir():
            return "not a directory"
        if not folder and out.is_dir():
            return "is a directory"
        if folder and not os.access(out, os.W_OK | os.X_OK):
            return "permission denied"
    ancestor = out.parent if not out.exists() or not folder else out
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        return f"{ancestor} is not a directory"
    if not os.access(ancestor, os.W_OK | os.X_OK):
        return "permission denied"
    return None


def _temporary_name(folder: Path, name: str) -> Path:
    return folder / f".{name}.{os.getpid()}-{secrets.token_hex(4)}{PARTIAL}"


def _make_parents(folder: Path, forced_exit: contextlib.ExitStack) -> list[Path]:
    """Makes ``folder`` and its missing parents, each removed (if empty) by a forced exit within
    ``forced_exit`` (:mod:`pluecker._ctrl_c`); returns those it made, innermost first."""
    made = []
    while not folder.exists():
        made.append(folder)
        folder = folder.parent
    for path in reversed(made):
        forced_exit.enter_context(_ctrl_c.removed_on_forced_exit(path, whole=False))
        path.mkdir()
    return made


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def _publish(stage: Path, out: Path) -> list[Path]:
    """Moves what ``stage`` holds into ``out`` (the folder renamed to ``out`` when there is none),
    replacing entries of the same name whole; returns the paths written, sorted."""
    names = sorted(p.name for p in stage.iterdir())
    if not out.exists() and not out.is_symlink():
        os.rename(stage, out)
        return [out / name for name in names]
    for name in names:
        entry, target = stage / name, out / name
        if target.is_dir() and not target.is_symlink():
            # A folder is replaced by renaming the old one aside first: never half of each.
            aside = _temporary_name(out, name)
            os.rename(target, aside)
            os.rename(entry, target)
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.replace(entry, target)
    stage.rmdir()
    return [out / name for name in names]


class Stage:
    """The temporary folder of :func:`staged` (``path``) and, once published, the paths written into
    ``out`` (``written``, sorted)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.written: list[Path] = []


@contextlib.contextmanager
def staged(out: str | os.PathLike, *, publish: bool = True) -> Iterator[Stage]:
    """A new empty temporary folder to write the output folder ``out`` into (``stage.path``): inside
    ``out`` when it exists, else beside it. When the block ends normally, what it holds is moved into
    ``out`` (the folder renamed to ``out`` when there is none; an entry of the same name replaced whole,
    other entries of ``out`` kept) and ``stage.written`` lists it; with ``publish=False`` it is removed
    instead (scratch space). When the block raises (an error, Ctrl-C), the temporary folder and the
    parents of ``out`` it had to make are removed: ``out`` is as it was."""
    out = Path(out)
    with contextlib.ExitStack() as forced_exit:
        made = [] if out.exists() else _make_parents(out.parent, forced_exit)
        try:
            path = _temporary_name(out if out.exists() else out.parent, out.name)
            forced_exit.enter_context(_ctrl_c.removed_on_forced_exit(path))
            path.mkdir()
        except BaseException:
            for folder in made:
                with contextlib.suppress(OSError):
                    folder.rmdir()
            raise
        stage = Stage(path)
        try:
            yield stage
            if publish:
                stage.written = _publish(path, out)
            else:
                _remove(path)
        except BaseException:
            _remove(path)
            for folder in made:
                with contextlib.suppress(OSError):
                    folder.rmdir()
            raise


def write_text(path: str | os.PathLike, text: str) -> None:
    """Writes ``text`` (UTF-8) to the file ``path`` through a temporary sibling renamed over it: an
    interrupted or failed write leaves ``path`` as it was."""
    path = Path(path)
    temporary = _temporary_name(path.parent, path.name)
    try:
        with _ctrl_c.removed_on_forced_exit(temporary):
            temporary.write_text(text, encoding="utf-8")
            os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
