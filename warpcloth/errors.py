"""The errors warpcloth raises, each with a message meant for the person who wrote the
input. The command line maps them to exit codes in one place (warpcloth.cli)."""

from __future__ import annotations

import os


class WarpclothError(Exception):
    """Base of every error warpcloth raises on purpose (bad input, a diverged run)."""


class SceneError(WarpclothError, ValueError):
    """A scene or material field is missing, unknown, mistyped or out of range.

    ``field`` is the dotted name of the offending field (e.g. ``strip.spacing_mm``),
    ``message`` what is wrong with it (and, once located, where it was set); ``related``
    the other fields a cross-field check read (one of them may be the one to change), and
    ``variant`` the sweep variant whose values failed.
    """

    def __init__(self, field: str, message: str, related: tuple[str, ...] = (), variant: int | None = None) -> None:
        self.field = field
        self.message = message
        self.related = related
        self.variant = variant
        super().__init__(f"{field}: {message}")


class ArgumentError(WarpclothError, ValueError):
    """An argument of a library function has an unusable value.

    ``argument`` is the Python parameter it was passed as (e.g. ``variants`` of
    :func:`warpcloth.run_sweep`), ``message`` what is wrong with it. The library names its
    own arguments, so a caller of a function reads the keyword it wrote; the command line
    turns the error into an :class:`OptionError` naming the option that supplied the
    argument, in one place (``warpcloth.cli.flags``, at its one error boundary).
    """

    def __init__(self, argument: str, message: str) -> None:
        self.argument = argument
        self.message = message
        super().__init__(f"{argument}: {message}")


class EnvironmentSettingError(WarpclothError, ValueError):
    """An environment variable warpcloth reads has an unusable value: ``variable`` is its
    name, ``message`` what is wrong with the value."""

    def __init__(self, variable: str, message: str) -> None:
        self.variable = variable
        self.message = message
        super().__init__(f"{variable}: {message}")


class ArgumentTypeError(ArgumentError, TypeError):
    """An argument of a library function has an unusable type (a string where a list is
    expected, a float where an index is).

    An :class:`ArgumentError` naming the argument, and a :class:`TypeError`, so code that
    catches either (``except TypeError`` written before the library named its arguments)
    catches it.
    """


class OptionError(ArgumentError):
    """A command-line option has an unusable value.

    ``option`` is the option as typed (e.g. ``--variants``) or a positional argument's
    name (``SCENE``). It is an :class:`ArgumentError` whose argument is the option, so
    ``except ArgumentError`` catches a library error and the command line's own alike.
    """

    def __init__(self, option: str, message: str) -> None:
        self.option = option
        super().__init__(option, message)


class DataFileError(WarpclothError, ValueError):
    """A data file (measurement, KES loop, run or sweep directory) cannot be used as it is.

    ``path`` names the file and ``line`` the 1-based line when one is to blame.
    """

    def __init__(self, path: str | os.PathLike[str], message: str, line: int | None = None) -> None:
        self.path = str(path)
        self.line = line
        where = self.path if line is None else f"{self.path}, line {line}"
        super().__init__(f"{where}: {message}")


class ResourceError(WarpclothError, ValueError):
    """The work asked for needs more memory or disk than there is; the message gives
    the numbers and what to change."""


class DivergenceError(WarpclothError, RuntimeError):
    """A strip's state became non-finite or physically absurd during a run.

    ``diverged`` lists one :class:`warpcloth.strip.Divergence` per diverged strip (strip,
    time, step, quantity, where, value); ``result`` holds everything recorded before the
    divergence.
    """

    def __init__(self, message: str, diverged: list, result: object = None) -> None:
        self.diverged = diverged
        self.result = result
        super().__init__(message)


class InternalError(WarpclothError, RuntimeError):
    """A check of warpcloth's own consistency failed: no input should reach it, so it is a
    bug in warpcloth (or a library it uses) to report, with the message and the command
    or call that raised it."""


class LongRunWarning(UserWarning):
    """A run long enough to be a mistake is about to start: its steps of each body and its
    estimated time, before the first launch (a run past ``integrator.max_steps`` is refused
    instead). The command line prints it as one line."""


class PlausibilityWarning(UserWarning):
    """A finite input outside the range a fabric strip or its measurement plausibly has
    (:data:`warpcloth.units.PLAUSIBLE`): it is used as given, and the warning names the
    value and the range. The command line prints it as one line."""


def checked_index(argument: str, value: object, count: int, what: str) -> int:
    """``value`` as an index of one of ``count`` ``what`` (0 … count − 1), or an
    ArgumentTypeError / ArgumentError naming ``argument``, the value and what is expected. A negative index is
    refused, as the command line refuses ``--variants -1``: it would pick from the end."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(argument, f"must be an integer index of the {count} {what}, got {value!r}")
    if not 0 <= int(value) < count:
        raise ArgumentError(argument, f"{value} is not one of the {count} {what} (0 to {count - 1})")
    return int(value)


def checked_path(argument: str, value: object) -> str | os.PathLike[str]:
    """``value`` if it is a path (a string or os.PathLike), else an ArgumentTypeError naming
    ``argument`` and what it got: a number or a result object passed where a file or
    directory belongs is refused where it enters, not deep in the file system's calls."""
    if isinstance(value, str | os.PathLike):
        return value
    raise ArgumentTypeError(
        argument, f"must be a path (a string or pathlib.Path), got {type(value).__name__} {value!r}"
    )


def checked_count(argument: str, value: object, minimum: int, meaning: str = "") -> int:
    """``value`` as a whole number of at least ``minimum``, or an ArgumentTypeError /
    ArgumentError naming ``argument`` and the value (a string "2" is not a count);
    ``meaning`` says what the least value does, e.g. " (0 runs the batches in this process)"."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(argument, f"must be a whole number ≥ {minimum}, got {type(value).__name__} {value!r}")
    if value < minimum:
        raise ArgumentError(argument, f"must be ≥ {minimum}{meaning}, got {value}")
    return int(value)


def checked_instance(argument: str, value: object, kind: type, made_by: str) -> None:
    """An ArgumentTypeError naming ``argument`` unless ``value`` is a ``kind`` (``made_by``
    says which call makes one)."""
    if not isinstance(value, kind):
        raise ArgumentTypeError(
            argument, f"must be a {kind.__name__} ({made_by} makes one), got {type(value).__name__} {value!r}"
        )
