"""Writing files so that a reader never sees half of one.

Each file is written under a hidden temporary name in the same directory, then renamed
over the final name (``os.replace`` is atomic on one file system). The temporary name
is unique to its writer (``.<name>.<pid>-<random>.tmp``), so two processes writing the
same file never share one; a crash leaves at worst such a ``.tmp`` file, which nothing
reads.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable
from pathlib import Path


def temporary_name(path: Path) -> Path:
    """A hidden name beside ``path`` that no other writer uses: ``.<name>.<pid>-<hex>.tmp``."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp")


def atomic_write(path: Path, write: Callable[[Path], object]) -> None:
    """Call ``write(tmp)`` to produce the file, then rename it to ``path``."""
    path = Path(path)
    tmp = temporary_name(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
