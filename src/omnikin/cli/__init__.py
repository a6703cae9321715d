"""Command-line interface ``omnikin`` (see ``omnikin --help``): one module per command.

Every command module has the same shape::

    def add_parser(sub, robot_help: str) -> None:
        '''Add the command to ``sub`` (argparse sub-parsers of :class:`~omnikin.cli.parser.CommandParser`);
        its parser's defaults name ``func=run``. ``robot_help``: the help of a ROBOT argument.'''

    def run(args) -> int:
        '''Run the parsed command; returns the exit status (errors are raised, never printed).'''

A command with commands of its own names their functions after them (``bag``: ``run_odometry``,
``run_export``; ``umbmark``: ``run_analyze``). A command calls the public API (:mod:`omnikin.api`)
where one exists and adds only what a command line needs: its options, their checks named as
typed, budgets, output files and printing.

* :mod:`~omnikin.cli.main`: the entry point; builds the parser from the command modules
  (:data:`~omnikin.cli.main.COMMANDS`) and hands it to :func:`omnikin.cli.process.run`.
* :mod:`~omnikin.cli.process`: the process around a command: signals, standard streams,
  warnings, one-line errors and exit statuses.
* :mod:`~omnikin.cli.parser`: the argument parser (one-line usage errors, "did you mean",
  negative numbers as values).
* :mod:`~omnikin.cli.common`: what several commands share (the robot, the console, declared
  outputs and inputs, JSON and table cells, option builders, number types);
  :mod:`~omnikin.cli.budget`: ``--max-memory`` and ``--max-time``.
* the commands: :mod:`~omnikin.cli.presets`, :mod:`~omnikin.cli.show`, :mod:`~omnikin.cli.ik`,
  :mod:`~omnikin.cli.fk`, :mod:`~omnikin.cli.odometry`, :mod:`~omnikin.cli.umbmark` (with
  ``umbmark analyze``), :mod:`~omnikin.cli.calibrate`, :mod:`~omnikin.cli.bag` (``bag odometry``,
  ``bag export``), :mod:`~omnikin.cli.simulate`, :mod:`~omnikin.cli.metrics`,
  :mod:`~omnikin.cli.ros`, :mod:`~omnikin.cli.sim`, :mod:`~omnikin.cli.view`,
  :mod:`~omnikin.cli.sweep`, :mod:`~omnikin.cli.mjcf`, :mod:`~omnikin.cli.urdf`.
"""
