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

__all__ = ["COMMANDS", "EXIT_INTERNAL", "EXIT_INTERRUPTED", "EXIT_USAGE", "build_parser", "main"]

EXIT_USAGE = 2
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

    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__, allow_abbrev=False)
    p.add_argument("--version", action="version", version=f"adaptive-dd {__version__}")
    p.add_argument("--debug", action="store_true", help="show the traceback of an internal error")
    sub = p.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"adaptive_dd.cli.{name}").add_parser(sub)
    return p


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
    """Run the CLI; returns the exit code (0 ok, 1 failed check, 2 user error, 3 internal error)."""
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)
    args.given = frozenset(a.split("=", 1)[0] for a in argv if a.startswith("--"))
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print(f"adaptive-dd {args.command}: interrupted; outputs left as before", file=sys.stderr)
        return EXIT_INTERRUPTED
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
