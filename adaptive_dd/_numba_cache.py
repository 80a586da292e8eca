"""Where numba caches the compiled kernels: one folder per state of the package's source.

numba's own cache (``cache=True``) is invalidated by the source file of the function it
compiled, not by the files of the functions that one calls: after an edit of, say, the
estimator kernel, the closed loop that inlines it would silently run the old code from
``__pycache__``. Keying the cache folder by a hash of every source file of the package
rules that out (a changed file gives a fresh folder and one compilation). The folder is
``$XDG_CACHE_HOME/adaptive_dd/numba/<hash>`` (``~/.cache`` by default); the 8 newest are kept.
Setting ``NUMBA_CACHE_DIR`` yourself turns this off.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

KEEP = 8


def source_hash(package: Path) -> str:
    """SHA-1 of every ``.py`` file of the package (names and contents), 16 hex digits."""
    h = hashlib.sha1()
    for f in sorted(package.rglob("*.py")):
        h.update(f.relative_to(package).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def configure() -> str | None:
    """Point numba's cache at the folder of this source state; returns it (None if left alone)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    package = Path(__file__).resolve().parent
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "adaptive_dd" / "numba"
    folder = base / source_hash(package)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not os.access(folder, os.W_OK):
            return None
    except OSError:
        return None
    import numba

    numba.config.CACHE_DIR = str(folder)
    try:
        old = sorted((p for p in base.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime)
        for p in old[:-KEEP]:
            if p != folder:
                shutil.rmtree(p, ignore_errors=True)
    except OSError:
        pass
    return str(folder)
