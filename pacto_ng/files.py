"""Files that are never half written, and run folders that are never silently mixed.

Atomic writes
    Every file of a run is written to a temporary file beside it (``NAME.tmp-PID.SUFFIX``, same
    folder, so the same file system), flushed to the disk (``fsync``) and renamed over the old
    one (``os.replace``, atomic on POSIX): a reader, or a process killed at any moment, sees the
    old file or the new one, never a part.  :func:`atomic_write_text` / :func:`atomic_write_bytes`
    for content in memory, :func:`atomic_path` for writers that need a path (matplotlib's
    ``savefig``, NGSolve's ``VTKOutput``, ``np.savez``, meshio): they write the temporary path
    the context manager yields, which is renamed when the block ends without an exception (and
    removed when it does not).  A failed write (disk full, file too large) raises
    :class:`WriteError`, a one-line :class:`~pacto_ng.params.InputError` naming the file.

The folder lock
    :class:`FolderLock` holds ``fcntl.flock`` on ``DIR/.pacto.lock`` while a process writes
    ``DIR``; a second process is refused at once.  The kernel releases the lock when the holder
    dies (even by ``kill -9``), so it is never left stuck; the (empty) lock file stays, except
    after a command that was refused before it wrote anything: it removes the lock file it
    created (``release(remove=True)``).

Run folders
    :func:`folder_outputs` lists what pacto wrote in a folder (a run is recognised by its
    ``params.json`` or ``checkpoint.npz``), :func:`refuse_reuse` refuses to write over it, and
    :func:`remove_outputs` (``--overwrite``) removes exactly the files pacto writes there
    (``analysis/`` and ``export/`` included), nothing else, and refuses when it is unsure.
"""
from __future__ import annotations

import contextlib
import errno
import json
import os
import re
from pathlib import Path

from .errors import InputError

#: the files a run (``pacto run``, ``pacto evaluate``, an analysis case) writes into its folder
RUN_FILES = ("params.json", "checkpoint.npz", "summary.json", "history.csv", "design.vtu",
             "design.png", "pressure.png", "materials.png", "convergence.png", "deformed.png",
             "part.stl", "part.png")
#: the files that mark a run folder (``pacto resume`` continues it)
RUN_MARKERS = ("params.json", "checkpoint.npz")
#: sub-folders the post-processing commands write into a run folder, and their files
RUN_SUBFOLDERS = {
    "analysis": ("analysis.json", "analysis.png", "analysis.csv", "report.md", "post.json",
                 "design.stl", "remeshed.vtu", "deformed.vtu", "deformed.png"),
    "export": ("design.stl", "design.vtk", "design.msh"),
}
LOCK_NAME = ".pacto.lock"
#: a temporary file of :func:`temp_path` (``design.tmp-1234.vtu``), and the name older
#: versions gave the checkpoint's (``checkpoint.npz.tmp.npz``)
_TEMP = re.compile(r"^(?P<stem>.+?)\.tmp-\d+(?P<suffix>\.[^.]*)?$")
_OLD_TEMPS = ("checkpoint.npz.tmp.npz",)
#: errors of a full disk or of a file size limit (``ulimit -f``)
NO_SPACE = tuple(getattr(errno, n) for n in ("ENOSPC", "EFBIG", "EDQUOT") if hasattr(errno, n))


class WriteError(InputError):
    """A file could not be written (a one-line message naming it; the old file is kept)."""

    def __init__(self, path, err: OSError | str):
        reason = err if isinstance(err, str) else (err.strerror or str(err))
        if isinstance(err, OSError) and err.errno in NO_SPACE:
            reason += ": the disk is full or a file size limit is reached"
        super().__init__(f"cannot write '{path}' ({reason})")
        self.path = Path(path)
        self.no_space = isinstance(err, OSError) and err.errno in NO_SPACE


# -- atomic writes -----------------------------------------------------------------------------
def temp_path(path: str | os.PathLike) -> Path:
    """The temporary file :func:`atomic_path` writes for ``path``: the same folder and suffix
    (writers choose their format by it), ``design.vtu`` -> ``design.tmp-PID.vtu``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.tmp-{os.getpid()}{path.suffix}")


def _fsync(path: Path, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    try:
        os.fsync(fd)
    except OSError:
        if not directory:  # some file systems cannot sync a folder: the rename is still atomic
            raise
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path to write ``path``'s new content to; on a clean exit it is synced
    and renamed to ``path``, on an exception (a failed write, an interrupt) removed, ``path``
    untouched.  An ``OSError`` of the write becomes a :class:`WriteError`.

    >>> with atomic_path(folder / "design.png") as tmp:      # doctest: +SKIP
    ...     fig.savefig(tmp)
    """
    path = Path(path)
    tmp = temp_path(path)
    try:
        yield tmp
        if not tmp.is_file():
            raise WriteError(path, "the writer wrote nothing")
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException as err:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(err, OSError):
            raise WriteError(path, err) from None
        raise
    with contextlib.suppress(OSError):
        _fsync(path.parent, directory=True)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        fh.write(data)


def atomic_write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    atomic_write_bytes(path, text.encode(encoding))


def check_tail(path: str | os.PathLike, ending: bytes, target: str | os.PathLike) -> None:
    """Raise :class:`WriteError` (naming ``target``, the file ``path`` is written for) unless
    ``path`` ends with ``ending`` (and white space): for writers that do not report a failed
    write (NGSolve's VTKOutput is C++ and ignores it)."""
    path, target = Path(path), Path(target)
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            fh.seek(max(0, size - len(ending) - 64))
            tail = fh.read().rstrip()
    except OSError as err:
        raise WriteError(target, err) from None
    if not tail.endswith(ending):
        raise WriteError(target, OSError(errno.EFBIG, "the file was cut short"))


# -- the folder lock ---------------------------------------------------------------------------
class FolderLock:
    """An exclusive lock on a folder for one writing process (``with FolderLock(dir, "run"):``).

    ``fcntl.flock`` on ``DIR/.pacto.lock``, taken without waiting: a folder another process
    holds gives a one-line :class:`~pacto_ng.params.InputError` naming that process.  The kernel
    drops the lock when its holder exits or is killed.  Without ``fcntl`` (Windows) no lock.

    ``created``: this lock made the lock file (the folder had none); ``release(remove=True)``
    then removes it, for a command that leaves the folder as it found it.  A lock file may so
    be removed while another process has it open: a lock taken on a file that is no longer the
    folder's lock file is dropped and taken again on the new one.
    """

    def __init__(self, folder: str | os.PathLike, command: str = "run"):
        self.folder = Path(folder)
        self.command = command
        self._fd = None
        self.created = False

    def _open(self, lock: Path) -> tuple[int, bool] | None:
        """A descriptor of the lock file and whether this call created it (None: the file
        went away between the two attempts)."""
        try:
            return os.open(lock, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644), True
        except FileExistsError:
            pass
        except OSError as err:
            raise InputError(f"--out: cannot lock '{self.folder}' ({err.strerror})") from None
        try:
            return os.open(lock, os.O_RDWR), False
        except FileNotFoundError:
            return None
        except OSError as err:
            raise InputError(f"--out: cannot lock '{self.folder}' ({err.strerror})") from None

    def acquire(self) -> "FolderLock":
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            return self
        lock = self.folder / LOCK_NAME
        for _ in range(100):
            opened = self._open(lock)
            if opened is None:
                continue
            fd, created = opened
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as err:
                holder = ""
                with contextlib.suppress(OSError, ValueError):
                    holder = os.pread(fd, 200, 0).decode().strip()
                os.close(fd)
                if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise InputError(f"--out: cannot lock '{self.folder}' "
                                     f"({err.strerror})") from None
                who = f"another pacto process ({holder})" if holder else "another pacto process"
                raise InputError(f"{self.command}: '{self.folder}' is being written by {who}: "
                                 "wait for it to end, or choose another --out") from None
            try:  # still the folder's lock file (not removed by a refused command meanwhile)
                current = os.path.samestat(os.fstat(fd), os.stat(lock))
            except OSError:
                current = False
            if current:
                break
            os.close(fd)
        else:
            raise InputError(f"--out: cannot lock '{self.folder}' (its lock file keeps "
                             "changing)")
        with contextlib.suppress(OSError):  # who holds it, for the message above
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"pid {os.getpid()}, pacto {self.command}\n".encode(), 0)
        self._fd, self.created = fd, created
        return self

    def release(self, *, remove: bool = False) -> None:
        """Drop the lock; with ``remove``, also remove the lock file if this lock created it
        (removed while still held, so that no other process locks the old file)."""
        if self._fd is not None:
            if remove and self.created:
                with contextlib.suppress(OSError):
                    (self.folder / LOCK_NAME).unlink()
            os.close(self._fd)  # closing the descriptor drops the flock
            self._fd = None

    def __enter__(self):
        return self if self._fd is not None else self.acquire()

    def __exit__(self, *exc):
        self.release()


# -- run folders -------------------------------------------------------------------------------
def folder_outputs(folder: str | os.PathLike) -> list[str]:
    """The files and sub-folders pacto writes that ``folder`` holds (names relative to it, in
    :data:`RUN_FILES` order, then ``analysis/`` and ``export/``).  Temporary files and the lock
    file are not counted."""
    folder = Path(folder)
    found = [n for n in RUN_FILES if (folder / n).is_file()]
    found += [n + "/" for n in RUN_SUBFOLDERS if (folder / n).is_dir()]
    return found


def is_run(folder: str | os.PathLike) -> bool:
    """``folder`` holds a run (its params.json or checkpoint.npz)."""
    return any((Path(folder) / n).is_file() for n in RUN_MARKERS)


def refuse_reuse(folder: str | os.PathLike, command: str) -> None:
    """Raise a one-line :class:`~pacto_ng.params.InputError` if ``folder`` holds what pacto
    wrote before (a run, or an evaluation's results), saying what to do instead."""
    found = folder_outputs(folder)
    if not found:
        return
    folder = Path(folder)
    shown = ", ".join(found[:4]) + (", ..." if len(found) > 4 else "")
    if is_run(folder):
        hint = f"continue it with 'pacto resume {folder}', " if command == "run" else ""
        raise InputError(f"{command}: '{folder}' already holds a run ({shown}): {hint}choose "
                         "another --out, or add --overwrite to remove that run's files first")
    raise InputError(f"{command}: '{folder}' already holds results ({shown}): choose another "
                     "--out, or add --overwrite to remove them first")


def _json_of_pacto(path: Path, keys: tuple) -> bool:
    """``path`` is JSON with all ``keys`` (or empty: the truncated file of an older version)."""
    try:
        text = path.read_text()
    except OSError:
        return False
    if not text.strip():
        return True
    try:
        data = json.loads(text)
    except ValueError:
        return False
    return isinstance(data, dict) and all(k in data for k in keys)


def cleanup_temps(folder: str | os.PathLike) -> list[str]:
    """Remove the temporary files of killed writers of pacto's files (``design.tmp-PID.vtu``
    beside ``design.vtu``) in ``folder`` and its sub-folders.  Call it holding the folder's
    lock.  Returns the names removed."""
    folder = Path(folder)
    removed = []
    for sub, names in (("", RUN_FILES), *RUN_SUBFOLDERS.items()):
        d = folder / sub if sub else folder
        if not d.is_dir():
            continue
        for entry in d.iterdir():
            m = _TEMP.match(entry.name)
            ours = entry.name in _OLD_TEMPS or (
                m is not None and m["stem"] + (m["suffix"] or "") in names)
            if ours and entry.is_file():
                with contextlib.suppress(OSError):
                    entry.unlink()
                    removed.append(str(entry.relative_to(folder)))
    return removed


def remove_outputs(folder: str | os.PathLike, command: str) -> list[str]:
    """``--overwrite``: remove the files pacto writes from ``folder`` (see :data:`RUN_FILES`,
    :data:`RUN_SUBFOLDERS`) and nothing else; refuse (a one-line InputError, nothing removed)
    when it is unsure they are pacto's: a params.json or summary.json that is not a run's, or a
    file of its own in ``analysis/`` or ``export/``.  Returns the names removed."""
    folder = Path(folder)
    for name, keys in (("params.json", ("case", "params")), ("summary.json", ("case",))):
        f = folder / name
        if f.is_file() and not _json_of_pacto(f, keys):
            raise InputError(f"{command} --overwrite: '{f}' was not written by pacto: nothing "
                             "removed (move it away, or choose another --out)")
    doomed = [folder / n for n in RUN_FILES if (folder / n).is_file()]
    subdirs = []
    for sub, names in RUN_SUBFOLDERS.items():
        d = folder / sub
        if not d.is_dir():
            continue
        for entry in sorted(d.iterdir()):
            m = _TEMP.match(entry.name)
            temp = m is not None and m["stem"] + (m["suffix"] or "") in names
            if not entry.is_file() or (entry.name not in names and not temp):
                raise InputError(f"{command} --overwrite: '{entry}' was not written by pacto: "
                                 "nothing removed (move it away, or choose another --out)")
            doomed.append(entry)
        subdirs.append(d)
    removed = cleanup_temps(folder)
    for f in doomed:
        f.unlink()
        removed.append(str(f.relative_to(folder)))
    for d in subdirs:
        d.rmdir()
        removed.append(d.name + "/")
    return removed


def claim_folder(folder: str | os.PathLike, command: str, *, overwrite: bool = False,
                 resume: bool = False) -> FolderLock:
    """Lock ``folder`` for ``command`` and make it ready to write: refuse a folder another
    process writes or one holding earlier results (unless ``resume``, or ``overwrite``: they
    are removed first); clear the temporary files of killed writers.  Returns the held lock
    (release it when done, or use it as a context manager).  A refused folder keeps no lock
    file this call made."""
    lock = FolderLock(folder, command).acquire()
    try:
        if overwrite:
            remove_outputs(folder, command)
        elif not resume:
            refuse_reuse(folder, command)
        cleanup_temps(folder)
    except BaseException:
        lock.release(remove=True)
        raise
    return lock
