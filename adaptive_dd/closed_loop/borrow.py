"""Arrays handed to the closed loop's sample loop without their reference counts.

Every array that the compiled sample loop reads out of a record (a NamedTuple field, a view, an
argument of a called kernel) costs numba a reference-count update, an atomic add on the array's
memory record, and numba's pruning pass removes only some of them: in a UR5 trial they were a
quarter of the loop's time (``perf``, ``NRT_incref`` and ``NRT_decref``). :func:`borrowed` gives
the same arrays without a memory record (a null meminfo, as numba gives a ``prange`` body its
arrays), so that each update is a test for null. The caller keeps the owners alive for as long
as the borrowed views are used: the loop's arguments (owned by the caller of the loop) and the
scratch it allocates, kept to the end of the loop by :func:`keep_alive`.
"""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.extending import intrinsic

__all__ = ["borrowed", "keep_alive"]

_PLAIN = (types.Number, types.Boolean, types.NoneType, types.EnumMember)


def _check(ty, where: str) -> None:
    if isinstance(ty, types.Array):
        return
    if isinstance(ty, types.BaseTuple):
        for k, t in enumerate(ty.types):
            _check(t, f"{where}[{k}]")
        return
    if not isinstance(ty, _PLAIN):
        raise TypingError(f"borrowed: {where} is {ty}: only arrays, tuples of them and plain scalars")


def _strip(context, builder, ty, val):
    """``val`` of type ``ty`` with every array's meminfo null (tuples walked member by member)."""
    if isinstance(ty, types.Array):
        ary = context.make_array(ty)(context, builder, value=val)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        return ary._getvalue()
    if isinstance(ty, types.BaseTuple):
        out = val
        for k, t in enumerate(ty.types):
            out = builder.insert_value(out, _strip(context, builder, t, builder.extract_value(val, k)), k)
        return out
    return val


@intrinsic
def borrowed(typingctx, x):
    """``x`` (an array, a tuple or NamedTuple of arrays, tuples and scalars) with its arrays'
    reference counts left out: the same data, shapes and strides. Valid while an owner of each
    array lives (an argument of the calling function, or a value kept by :func:`keep_alive`)."""
    _check(x, "the value")

    def codegen(context, builder, signature, args):
        return _strip(context, builder, x, args[0])

    return x(x), codegen


@intrinsic
def keep_alive(typingctx, x):
    """Nothing, at this point of the code: ``x`` lives at least until here (numba releases a
    value after its last use; a value whose arrays are :func:`borrowed` must outlive them)."""

    def codegen(context, builder, signature, args):
        return context.get_dummy_value()

    return types.none(x), codegen
