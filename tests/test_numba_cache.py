"""The compiled-kernel cache is keyed by the whole package source (stale kernels cannot run)."""

from __future__ import annotations

import numba

from adaptive_dd import _numba_cache


def test_any_source_change_gives_another_cache_folder(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    h0 = _numba_cache.source_hash(pkg)
    assert _numba_cache.source_hash(pkg) == h0
    (pkg / "sub" / "b.py").write_text("y = 3\n")  # a callee's file, not the caller's
    h1 = _numba_cache.source_hash(pkg)
    (pkg / "sub" / "b.py").rename(pkg / "b2.py")  # same bytes, another module
    assert len({h0, h1, _numba_cache.source_hash(pkg)}) == 3


def test_the_package_uses_its_folder_unless_the_user_sets_one(monkeypatch, tmp_path):
    from pathlib import Path

    import adaptive_dd

    expected = _numba_cache.source_hash(Path(adaptive_dd.__file__).parent)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    before = numba.config.CACHE_DIR
    try:
        folder = _numba_cache.configure()
        assert folder == str(tmp_path / "adaptive_dd" / "numba" / expected)
        assert numba.config.CACHE_DIR == folder
        monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
        assert _numba_cache.configure() is None
    finally:
        numba.config.CACHE_DIR = before
