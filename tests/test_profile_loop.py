"""benchmarks/profile_loop.py's names and perf map (the profile itself needs Linux perf and a fresh
compile: run by hand)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
try:
    from profile_loop import compiled_symbols, short_name, write_perf_map
finally:
    sys.path.pop(0)


def test_short_name_reads_numba_mangled_names():
    assert short_name("_ZN11adaptive_dd5plant9chain_rk44_rk4B4v284B90c8tJTIeFIjxB2IKSg") == (
        "adaptive_dd.plant.chain_rk4._rk4"
    )
    assert short_name("_ZN8__main__3fooB2v1E") == "__main__.foo"
    assert short_name("NRT_incref") == "NRT_incref"


def test_the_map_holds_a_function_compiled_here_at_its_address(tmp_path):
    @njit(cache=False)
    def _profiled_kernel(x):
        return np.sum(x) * 2.0

    assert _profiled_kernel(np.ones(3)) == 6.0
    syms = compiled_symbols()
    cres = next(iter(_profiled_kernel.overloads.values()))
    addr = cres.library.get_pointer_to_function(cres.fndesc.mangled_name)
    assert (addr, cres.fndesc.mangled_name) in syms
    path = tmp_path / "perf.map"
    assert write_perf_map(syms, str(path)) == len(syms)
    lines = {int(ln.split()[0], 16): ln.split(maxsplit=2) for ln in path.read_text().splitlines()}
    _, size, name = lines[addr]
    assert name.endswith("_profiled_kernel") and int(size, 16) > 0
    assert all(int(a, 16) > 0 for a, _, _ in lines.values())


def test_instruction_shares_bin_samples_by_offset_and_mnemonic():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    try:
        from profile_loop import instruction_shares
    finally:
        sys.path.pop(0)
    asm = """
Disassembly of section .data:

0000000000000000 <.data>:
   0:	55                   	push   %rbp
   1:	48 89 e5             	mov    %rsp,%rbp
   4:	ff d3                	call   *%rbx
   6:	ff d3                	call   *%rbx
   8:	c3                   	ret
"""
    shares, hot = instruction_shares(asm, [4, 4, 6, 1, 99], top=2)
    assert shares == [("call", 0.6), ("mov", 0.2)]  # of the 5 samples, one outside any instruction
    assert hot == [(4, "call   *%rbx", 0.4), (1, "mov    %rsp,%rbp", 0.2)]
