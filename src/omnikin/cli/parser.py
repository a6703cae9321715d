"""The argument parser of every ``omnikin`` sub-command: :mod:`argparse` with three habits fixed.

* **Errors are one line.** A usage error raises :class:`UsageError` (``omnikin.cli.process``
  prints it as ``omnikin: error: ik: ...; see 'omnikin ik --help'`` and exits 2) instead of
  argparse's usage block followed by the message.
* **Did you mean.** An unknown sub-command (``omnikin shwo``) or option (``omnikin ik --jsn``)
  names the closest known ones (:func:`omnikin.common.messages.did_you_mean`; argparse before Python
  3.14 has no suggestions).
* **Negative numbers are values.** ``omnikin ik tomasi-omni3 -2.5e-3 0 0``: argparse takes any
  argument that starts with ``-`` for an option unless it looks like ``-2`` or ``-2.5`` (it does
  not know ``-2.5e-3``, ``-1e3`` or ``-5M``). Its test for a negative number is replaced by
  :data:`NEGATIVE_NUMBER`, so these arguments are values, handed to the ``type`` as typed (the
  one argparse attribute this class sets). Nothing is added to or taken off an argument:
  ``" -1"`` is refused like ``" 1"``. (``--`` before the values, or ``--option=-1e3``, work too.)
* **Typed text is quoted shortened.** Every message that quotes an argument (an unknown command
  or option, an unexpected argument, an invalid choice, argparse's own messages) quotes at most
  :func:`omnikin.common.messages.shorten` of it, so that the reason after it survives the bounded error
  line of ``omnikin.cli.process``.
* **Options and positionals mix freely.** ``omnikin calibrate ROBOT --side 3 RUNS -o out.yaml``:
  a command without sub-commands is parsed like :meth:`argparse.ArgumentParser.parse_intermixed_args`
  (options first, then the positionals left, in order), so an optional positional after an
  option is not lost.

Sub-commands sit in argparse sub-parsers, which cannot share a parser with an optional
positional argument (``omnikin umbmark [ROBOT]`` and ``omnikin umbmark analyze FILE``);
:meth:`CommandParser.add_command` lets a first argument name such a command instead.

Options registered through argument groups are not offered as suggestions (none are used).
"""

from __future__ import annotations

import argparse
import re
import sys

from ..common.messages import did_you_mean, shorten
from ..errors import UsageError

NEGATIVE_NUMBER = re.compile(r"-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?[a-z]*|-(inf|infinity|nan)", re.IGNORECASE)
"""A negative number in Python's float syntax, or with a unit (matched in full): ``-2``,
``-2.5``, ``-.5``, ``-2.5e-3``, ``-1E3``, ``-inf``, ``-nan``, ``-5M``, ``-2h`` (no option of
omnikin starts with ``-`` and a digit). Such an argument is a value, never an option."""

_NEGATIVE_VALUE = re.compile(rf"(?:{NEGATIVE_NUMBER.pattern})\Z", re.IGNORECASE)
""":data:`NEGATIVE_NUMBER` in the form argparse applies its own test (``match``: the whole argument)."""

_PARSER = "_omnikin_parser"
"""Namespace attribute naming the innermost parser that ran (for suggestions), removed after parsing."""


QUOTE_LIMIT = 60
"""Longest argument a message quotes in full [characters] (:func:`omnikin.common.messages.shorten`'s cut)."""


class CommandParser(argparse.ArgumentParser):
    """:class:`argparse.ArgumentParser` with one-line errors, suggestions and negative numbers
    as values (module docstring). Sub-parsers made with :meth:`add_subparsers` are of this
    class too."""

    def __init__(self, *args, **kwargs):
        self._option_names: list[str] = []  # before argparse adds -h/--help through add_argument
        self._commands: dict[str, CommandParser] = {}
        self._subcommands = None
        self._passes = False  # inside the two passes of argparse's intermixed parsing
        self._typed: list[str] = []  # the arguments this parser was given, for bounded messages
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_VALUE  # argparse's test: a value, not an option
        for parent in kwargs.get("parents", ()):
            self._option_names += getattr(parent, "option_names", [])

    # --- what the parser knows -------------------------------------------------------------------
    @property
    def option_names(self) -> list[str]:
        """Every option string (``--json``, ``-o``, ...) added with :meth:`add_argument`."""
        return list(self._option_names)

    @property
    def command_name(self) -> str:
        """The sub-command this parser reads (``"bag odometry"``), from its ``prog``."""
        words = self.prog.split()
        return " ".join(words[1:])

    def add_argument(self, *args, **kwargs):
        action = super().add_argument(*args, **kwargs)
        self._option_names += list(action.option_strings)
        return action

    def add_subparsers(self, **kwargs):
        self._subcommands = super().add_subparsers(**kwargs)
        return self._subcommands

    def add_command(self, name: str, parser: CommandParser) -> None:
        """Let a first argument ``name`` select ``parser`` (beside this parser's own arguments,
        which may include an optional positional that argparse's sub-parsers cannot follow)."""
        self._commands[name] = parser

    @property
    def command_names(self) -> list[str]:
        """The names of the sub-commands (argparse sub-parsers and :meth:`add_command`)."""
        names = list(self._commands)
        if self._subcommands is not None:
            names += list(self._subcommands.choices)
        return names

    # --- parsing ---------------------------------------------------------------------------------------
    def parse_known_args(self, args=None, namespace=None):
        if self._passes:  # a pass of parse_known_intermixed_args
            return super().parse_known_args(args, namespace)
        args = [str(a) for a in (sys.argv[1:] if args is None else args)]
        self._typed = args
        if args and args[0] in self._commands:
            return self._commands[args[0]].parse_known_args(args[1:], namespace)
        self._check_command(args)
        namespace, extras = self._parse_mixed(args, namespace)
        if not hasattr(namespace, _PARSER):
            setattr(namespace, _PARSER, self)
        return namespace, extras

    def parse_args(self, args=None, namespace=None):
        namespace, extras = self.parse_known_args(args, namespace)
        innermost = getattr(namespace, _PARSER, self)
        delattr(namespace, _PARSER)
        if extras:
            innermost.error(innermost._unrecognized(extras))
        return namespace

    def _parse_mixed(self, args: list[str], namespace):
        """argparse's intermixed parsing where the parser allows it (no sub-commands, no
        positional taking the remainder), else its plain parsing."""
        if self._subcommands is not None or any(
            a.nargs in (argparse.PARSER, argparse.REMAINDER) for a in self._get_positional_actions()
        ):
            return super().parse_known_args(args, namespace)
        self._passes = True
        try:
            return super().parse_known_intermixed_args(args, namespace)
        finally:
            self._passes = False

    def _check_value(self, action, value):
        """argparse's check of ``choices``, quoting the value shortened, with suggestions."""
        if action.choices is not None and value not in action.choices:
            names = [str(c) for c in action.choices]
            raise argparse.ArgumentError(
                action,
                f"invalid choice: {shorten(value)}{did_you_mean(value, names)} (choose from {', '.join(names)})",
            )

    def error(self, message: str):
        """Raise :class:`UsageError` (argparse would print the usage block and exit), every typed
        argument in ``message`` quoted shortened (:meth:`_bounded`)."""
        raise UsageError(self._bounded(message), command=self.command_name)

    # --- messages ---------------------------------------------------------------------------------------
    def _bounded(self, message: str) -> str:
        """``message`` with each long argument this parser was given (or its value after ``=``,
        or after a one-letter option such as ``-oFILE``) quoted as :func:`shorten` quotes it:
        argparse's own messages quote values in full (``ignored explicit argument``, ``invalid
        int value``)."""
        for typed in sorted(set(self._typed), key=len, reverse=True):
            for text in (typed, typed.partition("=")[2], typed[2:]):
                if len(text) > QUOTE_LIMIT and text in message:
                    message = message.replace(repr(text), shorten(text)).replace(text, shorten(text))
        return message

    def _check_command(self, args: list[str]) -> None:
        """An unknown sub-command is named with the closest known ones (the first argument that
        is not an option; no parser of omnikin has an option with a value before its sub-command)."""
        if self._subcommands is None:
            return
        word = next((a for a in args if not a.startswith("-") or _NEGATIVE_VALUE.match(a)), None)
        names = self.command_names
        if word is not None and word not in names:
            self.error(f"unknown command {shorten(word)}{did_you_mean(word, names)} (commands: {', '.join(names)})")

    def _unrecognized(self, extras: list[str]) -> str:
        first = extras[0]
        if first.startswith("-") and not _NEGATIVE_VALUE.match(first):
            name = first.split("=", 1)[0]
            message = f"unknown option {shorten(name)}{did_you_mean(name, self._option_names)}"
        else:
            message = f"unexpected argument {shorten(first)}"
        if len(extras) > 1:
            message += f" (and {len(extras) - 1} more argument(s))"
        return message
