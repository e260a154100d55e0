"""One run at a time per output folder (docs/limits.md): ``DIR/.nsd.lock``, held with ``flock`` for the
whole command, names the holder's pid. A second run into the same --out finds it held and exits 2
at once naming that pid; the kernel drops the lock when its process ends in any way (SIGKILL
included), so a lock left by a killed run is stale by construction: the next run takes it over
(and says so on stderr). The lock file is removed when the command ends, and so are the folders
the command made for it if they stayed empty (bad input found later writes nothing).
"""
from __future__ import annotations

import fcntl
import os
import sys
from pathlib import Path

from nsd_core.common.files import printable
from nsd_core.device.params import ParameterError

LOCK_NAME = ".nsd.lock"
_held: list[tuple[int, Path, list[Path]]] = []  # (fd, lock file, folders made for it, deepest last)


def _make_folders(folder: Path) -> list[Path]:
    missing = []
    p = folder.absolute()
    while not p.exists():
        missing.append(p)
        p = p.parent
    for m in reversed(missing):
        os.mkdir(m)
    return list(reversed(missing))


def _holder(fd: int) -> str:
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        return os.read(fd, 200).decode("utf-8", "replace").split("\n")[0].strip()
    except OSError:
        return ""


def acquire(folder: Path, option: str, value: str) -> None:
    """Hold DIR/.nsd.lock for this process (ParameterError naming the holder's pid when another run has it)."""
    folder = Path(folder)
    for held_fd, lock, _ in _held:
        if lock.parent.resolve() == folder.resolve():
            return  # already ours (a command checking its folder twice)
    created = _make_folders(folder)
    lock = folder / LOCK_NAME
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _holder(fd)
            os.close(fd)
            raise ParameterError(f"{option} {printable(value)}: another nsd run is writing there (pid "
                                 f"{pid or 'unknown'}); wait for it to finish or choose another folder") from None
        try:
            same = os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the holder removed the file as we opened it: take the new one
    previous = _holder(fd)
    try:  # the pid is for the message of a run that finds the lock held; the flock is the lock
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()}\n{printable(' '.join(sys.argv))}\n".encode())
    except OSError:
        pass  # a full disk: the run goes on and its first result says so (exit 1, naming the file)
    _held.append((fd, lock, created))
    if previous and previous != str(os.getpid()):
        print(f"nsd: note: {printable(folder)} was locked by pid {previous}, which no longer runs; lock taken over",
              file=sys.stderr)


def release_all() -> None:
    """Remove and release every lock this process holds; remove the folders made for them if empty."""
    while _held:
        fd, lock, created = _held.pop()
        try:
            if os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino:
                os.unlink(lock)
        except OSError:
            pass
        os.close(fd)
        for d in reversed(created):  # deepest first
            try:
                os.rmdir(d)
            except OSError:
                break
