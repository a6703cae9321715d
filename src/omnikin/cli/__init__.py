"""Command-line interface ``omnikin`` (see ``omnikin --help``)."""
