"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark,sweep,validate,...}``.

Exit codes: 0 success, 1 a check or an estimate failed, 2 a user error (bad option,
scenario, record or output path; one line naming the problem), 3 an internal error
(a short message; the traceback with ``--debug``), 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import traceback
from pathlib import Path

from adaptive_dd.errors import OutputError, ParameterError

__all__ = [
    "COMMANDS",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_PIPE",
    "EXIT_USAGE",
    "build_parser",
    "console",
    "main",
]

EXIT_USAGE = 2
EXIT_PIPE = 141
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130
ISSUE_TRACKER = "the adaptive_dd issue tracker"

#: The commands, in the order ``--help`` lists them: each is the module
#: ``adaptive_dd.cli.<name>``, with ``add_parser(sub)`` (its options) and ``run(args) -> int``.
COMMANDS = (
    "check",
    "simulate",
    "reproduce",
    "identify",
    "predict",
    "excite",
    "benchmark",
    "validate",
    "sweep",
    "leaderboard",
)


def build_parser() -> argparse.ArgumentParser:
    """The ``adaptive-dd`` parser (no abbreviations of options; checked numeric options)."""
    from adaptive_dd import __version__

    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__.replace("``", ""), allow_abbrev=False)
    p.add_argument("--version", action="version", version=f"adaptive-dd {__version__}")
    p.add_argument("--debug", action="store_true", help="show the traceback of an internal error")
    sub = p.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"adaptive_dd.cli.{name}").add_parser(sub)
    return p


def _unknown_options(parser: argparse.ArgumentParser, command: str, unknown: list[str]) -> None:
    """Exit 2 naming the unknown arguments with the command's usage and, for a mistyped option, the
    command's options nearest to it (``--seed``: did you mean ``--seeds``)."""
    import difflib

    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    options = [o for a in sub._actions for o in a.option_strings if o.startswith("--")]
    near = {
        u: difflib.get_close_matches(u.split("=", 1)[0], options, n=2, cutoff=0.6)
        for u in unknown
        if u.startswith("-")
    }
    hints = "; ".join(f"{u}: did you mean {' or '.join(m)}?" for u, m in near.items() if m)
    sub.error(f"unrecognized arguments: {' '.join(unknown)}" + (f" ({hints})" if hints else ""))


def _repeated_options(parser: argparse.ArgumentParser, command: str, argv: list[str]) -> None:
    """Exit 2 naming an option given twice that takes one value (``--seeds 5 --seeds 10`` ran 10
    seeds without a word); options meant to repeat (append, count) may."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    action_of = {o: a for a in sub._actions for o in a.option_strings}
    seen: dict = {}
    for token in argv[: argv.index("--")] if "--" in argv else argv:
        action = action_of.get(token.split("=", 1)[0]) if token.startswith("-") else None
        if action is None or isinstance(action, argparse._AppendAction | argparse._CountAction):
            continue
        seen.setdefault(action.dest, []).append(token.split("=", 1)[0])
    twice = [names for names in seen.values() if len(names) > 1]
    if twice:
        said = "; ".join(f"{' and '.join(dict.fromkeys(n))} given {len(n)} times" for n in twice)
        sub.error(f"{said}: give each option once (the last would silently win)")


def _is_user_error(exc: BaseException) -> bool:
    """Our errors, file-system errors, and plain ValueErrors raised by adaptive_dd's own code."""
    from adaptive_dd.errors import DataError, ScenarioError, SignalError, UrdfError

    errors = ParameterError | ScenarioError | DataError | SignalError | OutputError | UrdfError | OSError
    if isinstance(exc, errors):
        return True
    if type(exc) is ValueError and exc.__traceback__ is not None:
        last = traceback.extract_tb(exc.__traceback__)[-1].filename
        package = Path(__file__).resolve().parent.parent  # adaptive_dd/, not adaptive_dd/cli/
        return Path(last).resolve().is_relative_to(package)
    return False


def _user_message(exc: BaseException) -> str:
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return f"{where}{exc.strerror or exc}"
    return str(exc)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 failed check, 2 user error, 3 internal error,
    141 its output's reader stopped early, as a command killed by SIGPIPE)."""
    import os

    os.environ.setdefault("MPLBACKEND", "Agg")  # the command writes its figures to files; no window
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # the command's own usage, and the option meant (no abbreviations are taken)
        _unknown_options(parser, args.command, unknown)
    _repeated_options(parser, args.command, argv)
    args.given = frozenset(a.split("=", 1)[0] for a in argv if a.startswith("--"))
    args.argv = tuple(argv)  # the command as typed, for the outputs that record it
    empty = [o for o in sorted(args.given) if getattr(args, o[2:].replace("-", "_"), None) == ""]
    if empty:  # an empty path or address: never read as "not given" (--out "" wrote into the working folder)
        print(f"adaptive-dd {args.command}: error: {', '.join(empty)}: an empty value; give one, or leave "
              "the option out for its default", file=sys.stderr)  # fmt: skip
        return EXIT_USAGE
    import signal
    import threading

    term = None
    if threading.current_thread() is threading.main_thread():  # SIGTERM (timeout, CI, systemd) as Ctrl-C:
        term = signal.signal(signal.SIGTERM, _terminated)  # the partial outputs removed, not left behind
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        kept = (
            "; the finished cells are kept in OUT/cells: the same command resumes from them"
            if args.command == "sweep"
            else ""
        )
        print(f"adaptive-dd {args.command}: interrupted; outputs left as before{kept}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader stopped early (| head): quiet, as a tool killed by SIGPIPE
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # the interpreter's last flush too
        return EXIT_PIPE
    except Exception as exc:
        if _is_user_error(exc):  # our errors name what was wrong and where
            print(f"adaptive-dd {args.command}: error: {_user_message(exc)}", file=sys.stderr)
            return EXIT_USAGE
        if args.debug:
            traceback.print_exc()
        print(
            f"adaptive-dd {args.command}: internal error: {type(exc).__name__}: {exc}; please report it "
            f"at {ISSUE_TRACKER}, rerun with --debug for the traceback",
            file=sys.stderr,
        )
        return EXIT_INTERNAL
    finally:
        if term is not None:
            signal.signal(signal.SIGTERM, term)


def _terminated(signum, frame) -> None:
    """SIGTERM raised as Ctrl-C's KeyboardInterrupt: the run stops the same way (outputs as before)."""
    raise KeyboardInterrupt


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """The command's own warnings (a category of this package: a URDF's unusual value) on one line,
    ``adaptive-dd: warning: ...``, without Python's source line; any other as Python shows it."""
    if category.__module__.startswith("adaptive_dd"):
        print(f"adaptive-dd: warning: {message}", file=sys.stderr if file is None else file)
    else:
        _SHOW_WARNING(message, category, filename, lineno, file, line)


_SHOW_WARNING = __import__("warnings").showwarning


def console() -> None:
    """The ``adaptive-dd`` command: :func:`main`, then the process ends without tearing down
    its modules.

    A run leaves hundreds of compiled functions and their LLVM modules loaded; the interpreter's
    teardown of them took about 0.45 s of a 3-s warm run of the default scenario. Everything a
    command writes is closed when :func:`main` returns (its outputs are staged and moved in a
    context); before the process ends, the threads that are not daemons are joined, the
    ``atexit`` handlers run (multiprocessing's, Dask's, ``weakref.finalize``'s) and the
    standard streams are flushed. In-process callers use :func:`main`, which returns."""
    import atexit
    import os
    import threading
    import warnings

    warnings.showwarning = _show_warning
    code = main()
    for t in threading.enumerate():
        if t is not threading.main_thread() and not t.daemon:
            t.join()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except BrokenPipeError:  # the reader stopped before the last of it: as main() says
            code = EXIT_PIPE
        except (OSError, ValueError):  # a stream closed under us: what it held is lost
            code = code or 1
    os._exit(code)
