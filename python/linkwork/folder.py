"""Output folders written whole: a run's files go into a staging folder beside the output folder,
which then takes the output folder's place in one step, so that a reader finds one run's complete
files, the new run's or the previous one's, whatever stops the writer (kill -9, a full disk, an
error).

A folder is claimed (:func:`claim`) before anything is computed: its parent must be writable
(the staging folder, ``.<name>.linkwork-<pid>``, is created then), and a lock file beside it
(``.<name>.linkwork.lock``, held with ``flock`` while the claim lasts) keeps a second run out,
naming the first. :meth:`Folder.commit` swaps the staging folder with the output folder
(``renameat2(RENAME_EXCHANGE)`` on Linux) and removes the old one; where the system cannot swap
two folders, the old one is renamed aside first (``.<name>.linkwork-<pid>.old``), and the next
claim puts it back if a crash left no output folder. The next claim also removes what a killed
run left beside the folder (its staging folder, with the rows it had streamed).

A folder that holds files no run writes is refused rather than replaced: replacing it would
delete them.

A single file is written whole as well (:func:`write_text`): to a temporary name, then renamed.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import os
import shutil
import stat
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from .errors import FileError

if sys.platform == "win32":
    import msvcrt
else:
    import fcntl

RUN_FILES = frozenset(
    {
        "results.csv", "results.parquet", "summary.json", "modes.csv", "model.yaml", "report.html",
        "sensitivities.csv", "sensitivities.parquet",
    }
)
"""What ``linkwork run`` (``Results.write``) writes at the top of its folder (tables the model
names are added by path)."""

SWEEP_FILES = frozenset({"sweep.parquet"})
"""What ``linkwork sweep`` writes into its folder."""

TOLERANCE_FILES = frozenset({"tolerance.json", "report.html"})
"""What ``linkwork tolerance`` writes into its folder."""

_MARK = ".linkwork"
"""What the names of the files beside an output folder carry, after its own name."""

# renameat2(2): both paths relative to the working directory; swap the two names.
_AT_FDCWD = -100
_RENAME_EXCHANGE = 2

# The folders claimed by this process, by absolute path: `Results.write` finds the command
# line's claim here (made before the run, with a stream in its staging folder).
_claimed: dict[Path, Folder] = {}


class Folder:
    """An output folder claimed by this process: locked, with an empty staging folder
    (:attr:`staging`) to write the run's files into, until :meth:`commit` or :meth:`release`."""

    def __init__(self, target: Path, lock: int, staging: Path | None) -> None:
        self.target = target
        self._lock = lock
        self.staging = staging

    def commit(self) -> None:
        """Make the staging folder the output folder, in one step a reader cannot see half of,
        and remove the previous one; then release the claim."""
        if self.staging is None:
            raise ValueError(f"{self.target}: claimed without a staging folder; nothing to commit")
        try:
            _swap(self.staging, self.target)
        except OSError as error:
            raise FileError(f"{self.target}: cannot replace the output folder: {error}") from error
        finally:
            self.release()

    def release(self) -> None:
        """Remove the staging folder (when not committed) and the lock."""
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        if _claimed.get(self.target) is self:
            del _claimed[self.target]
            # Removed before it is unlocked: a run waiting on this inode sees it gone and retries.
            with contextlib.suppress(OSError):
                _lock_path(self.target).unlink()
            os.close(self._lock)


def inside(table: str) -> bool:
    """Whether a table the model names by ``table`` is inside the model's folder: such a table
    is copied into the output folder, at the same path."""
    path = Path(table)
    return not path.is_absolute() and ".." not in path.parts


def run_files(tables: Iterable[str]) -> frozenset[str]:
    """What a run writes into its folder: :data:`RUN_FILES` and the model's ``tables`` inside
    its folder."""
    return RUN_FILES | {t for t in tables if inside(t)}


def absolute(path: str | os.PathLike[str]) -> Path:
    """``path`` absolute, its links resolved: the folder a swap replaces is the real one."""
    return Path(os.path.realpath(os.fspath(path)))


def claimed(path: str | os.PathLike[str]) -> Folder | None:
    """This process's claim on the folder at ``path``, if it has one."""
    return _claimed.get(absolute(path))


def claim(path: str | os.PathLike[str], files: Iterable[str] = RUN_FILES, stage: bool = True) -> Folder:
    """Claim the output folder at ``path`` (its parents created): lock it, and with ``stage``
    create its staging folder (without, the folder must exist: a report is rebuilt in it). A :class:`FileError` with one line when it cannot be written,
    when another run holds it (named by its process id and command), or when it holds entries
    that are none of ``files`` (names at its top, or paths of tables inside it)."""
    target = absolute(path)
    if target.parent == target:
        raise FileError(f"{target}: cannot be an output folder (a run replaces its output folder whole)")
    if not stage and not target.is_dir():
        raise FileError(f"{target}: no such folder")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise _unwritable(target, error) from error
    if target.exists() and not target.is_dir():
        raise FileError(f"{target}: not a folder")
    lock = _lock(target)
    folder = Folder(target, lock, None)
    _claimed[target] = folder
    try:
        _recover(target)
        if target.exists() and not os.access(target, os.W_OK):
            raise _unwritable(target, PermissionError(errno.EACCES, os.strerror(errno.EACCES)))
        if stage:
            _refuse_foreign(target, files)
            staging = target.with_name(f".{target.name}{_MARK}-{os.getpid()}")
            shutil.rmtree(staging, ignore_errors=True)
            staging.mkdir()
            folder.staging = staging
            if target.exists():
                # The folder that takes its place keeps its permissions (a folder shared by a group).
                staging.chmod(stat.S_IMODE(target.stat().st_mode))
    except OSError as error:
        folder.release()
        if isinstance(error, FileError):
            raise
        raise _unwritable(target, error) from error
    except BaseException:
        folder.release()
        raise
    return folder


@contextlib.contextmanager
def writing(path: str | os.PathLike[str], files: Iterable[str] = RUN_FILES) -> Iterator[Path]:
    """The staging folder to write the files of the folder at ``path`` into: this process's
    claim on it, or a claim made here; committed when the block ends well, else released (the
    previous folder stays). An ``OSError`` in the block is a :class:`FileError` naming the
    folder."""
    folder = claimed(path) or claim(path, files)
    if folder.staging is None:
        raise ValueError(f"{folder.target}: claimed without a staging folder")
    try:
        yield folder.staging
    except FileError:
        folder.release()
        raise
    except OSError as error:
        folder.release()
        raise FileError(f"{folder.target}: cannot write the output: {error}") from error
    except BaseException:
        folder.release()
        raise
    folder.commit()


def _unwritable(target: Path, error: OSError) -> FileError:
    """The one line for an output folder that cannot be written (it, or the folder it is in)."""
    return FileError(f"{target}: cannot write the output folder: {error.strerror or error}")


def _lock_path(target: Path) -> Path:
    return target.with_name(f".{target.name}{_MARK}.lock")


def _lock(target: Path) -> int:
    """Take the lock of ``target`` (not waiting): its file descriptor, the file holding this
    process's id and command. Held by another, a :class:`FileError` naming it."""
    path = _lock_path(target)
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise _unwritable(target, error) from error
        try:
            locked = _try_lock(fd)
        except OSError as error:
            os.close(fd)
            raise _unwritable(target, error) from error
        if not locked:
            holder = _read(fd) or "another process"
            os.close(fd)
            raise FileError(f"{target}: another run is writing this output folder ({holder}); wait for it or give another folder") from None
        # The holder before may have removed the file between our open and lock: then lock anew.
        try:
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.lseek(fd, 0, os.SEEK_SET)
    os.write(fd, f"pid {os.getpid()}: {' '.join(sys.argv)}".encode())
    return fd


def _try_lock(fd: int) -> bool:
    """Lock the open file ``fd`` for this process, not waiting: False when another holds it.
    (Windows, untested here: the first byte, locked with ``msvcrt.locking``.)"""
    try:
        if sys.platform == "win32":
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        else:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        if error.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK, errno.EDEADLK):
            return False
        raise
    return True


def _read(fd: int) -> str:
    """What the lock file ``fd`` says of its holder."""
    with contextlib.suppress(OSError):
        os.lseek(fd, 0, os.SEEK_SET)
        return os.read(fd, 4096).decode(errors="replace").strip()
    return ""


def _beside(target: Path) -> list[Path]:
    """What runs of ``target`` left beside it: staging folders and folders renamed aside."""
    prefix = f".{target.name}{_MARK}-"
    return [p for p in target.parent.iterdir() if p.name.startswith(prefix)]


def _recover(target: Path) -> None:
    """Under the lock: put back a previous folder a crash left renamed aside with no output
    folder in its place, and remove what killed runs left beside it."""
    left = _beside(target)
    aside = [p for p in left if p.name.endswith(".old")]
    if aside and not target.exists():
        os.rename(aside[0], target)
        left.remove(aside[0])
    for p in left:
        shutil.rmtree(p, ignore_errors=True)


def _refuse_foreign(target: Path, files: Iterable[str]) -> None:
    """A :class:`FileError` when ``target`` holds what a run does not write."""
    if not target.is_dir():
        return
    allowed = {Path(f) for f in files}
    roots = {f.parts[0] for f in allowed}
    foreign = []
    for entry in sorted(target.iterdir()):
        if entry.name not in roots:
            foreign.append(entry.name)
        elif entry.is_dir() and not entry.is_symlink():
            for sub in sorted(entry.rglob("*")):
                if not sub.is_dir() and sub.relative_to(target) not in allowed:
                    foreign.append(str(sub.relative_to(target)))
    if foreign:
        shown = ", ".join(foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
        raise FileError(
            f"{target}: holds {shown}, which a run does not write; a run replaces its output folder whole, "
            "so give a new or empty folder, or one an earlier run wrote"
        )


def _exchange(a: Path, b: Path) -> bool:
    """Swap the folders at ``a`` and ``b`` in one step (Linux's ``renameat2``); False where the
    system or the file system cannot."""
    rename = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None) if sys.platform == "linux" else None
    if rename is None:
        return False
    if rename(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def _swap(staging: Path, target: Path) -> None:
    """``staging`` becomes ``target``; the previous ``target`` is removed."""
    if not target.exists():
        os.rename(staging, target)
        return
    if _exchange(staging, target):
        shutil.rmtree(staging, ignore_errors=True)
        return
    aside = staging.with_name(staging.name + ".old")
    os.rename(target, aside)
    os.rename(staging, target)
    shutil.rmtree(aside, ignore_errors=True)


def write_text(path: Any, text: str) -> None:
    """Write ``text`` to ``path`` whole, then rename it into place, as the engine writes its files."""
    path = Path(path)
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        temp.write_text(text, encoding="utf-8")
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)
