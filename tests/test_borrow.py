"""The closed loop's borrowed arrays (:mod:`adaptive_dd.closed_loop.borrow`): the same data
without reference counts, the owners kept alive, anything else refused."""

from __future__ import annotations

import gc
import sys
from typing import NamedTuple

import numpy as np
import pytest
from numba import njit, types
from numba.core.errors import TypingError
from numba.extending import intrinsic

from adaptive_dd.closed_loop.borrow import borrowed, keep_alive


class Inner(NamedTuple):
    a: np.ndarray
    b: np.ndarray


class Outer(NamedTuple):
    inner: Inner
    x: np.ndarray
    flag: bool
    k: int


@njit
def _write_through(o):
    b = borrowed(o)
    for j in range(b.k):
        b.inner.b[j] += b.inner.a[j] * b.x[j] + (1.0 if b.flag else 0.0)
    return b.inner.b[1:].sum()


@njit
def _meminfos(o):
    """1 where the array carries a memory record (its meminfo), per array, before and after."""
    b = borrowed(o)
    return np.array([_has_meminfo(o.x), _has_meminfo(b.x), _has_meminfo(b.inner.a)])


@intrinsic
def _has_meminfo(typingctx, arr):
    def codegen(context, builder, signature, args):
        ary = context.make_array(arr)(context, builder, value=args[0])
        null = builder.icmp_unsigned("==", ary.meminfo, ary.meminfo.type(None))
        zero, one = context.get_constant(types.int64, 0), context.get_constant(types.int64, 1)
        return builder.select(null, zero, one)

    return types.int64(arr), codegen


def _outer():
    return Outer(Inner(np.arange(4.0), np.zeros(4)), np.full(4, 2.0), True, 4)


def test_borrowed_arrays_are_the_same_memory_without_a_reference_count():
    o = _outer()
    refs = [sys.getrefcount(a) for a in (o.inner.a, o.inner.b, o.x)]
    assert _write_through(o) == pytest.approx(3.0 + 5.0 + 7.0)
    np.testing.assert_array_equal(o.inner.b, [1.0, 3.0, 5.0, 7.0])  # written through the borrowed view
    assert [sys.getrefcount(a) for a in (o.inner.a, o.inner.b, o.x)] == refs  # nothing leaked or lost
    assert list(_meminfos(o)) == [1, 0, 0]


@njit
def _scratch_sum(n):
    owned = (np.ones(n), (np.full(n, 2.0), np.zeros((2, n))))
    ones, (twos, grid) = borrowed(owned)
    for _ in range(3):  # allocations in between: freed memory would be handed out again here
        junk = np.full(n, -1.0)
        grid[0, 0] += junk[0]
    total = ones.sum() + twos.sum() + grid[0, 0]
    keep_alive(owned)
    return total


def test_scratch_kept_alive_is_still_the_scratch_after_allocations():
    assert _scratch_sum(1000) == pytest.approx(1000.0 + 2000.0 - 3.0)
    gc.collect()


@njit
def _bad(x):
    return borrowed(x)


def test_a_value_with_a_reference_counted_member_it_cannot_borrow_is_refused():
    from numba.typed import List

    lst = List([1.0, 2.0])
    with pytest.raises(TypingError, match=r"borrowed: the value\[1\] is .*only arrays, tuples of them"):
        _bad((np.zeros(2), lst))
