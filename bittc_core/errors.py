"""Errors that carry a message meant for the user.

Library code raises ``BittcError`` subclasses whose messages name the bad value or field
(never a command-line flag); only ``sim.cli`` raises ``CliError``, which names the
flag. ``bittc`` prints either kind without a traceback and exits with status 2."""


class BittcError(Exception):
    """A bad input or an impossible request: the message names the bad value."""


class ConfigError(BittcError, ValueError):
    """A scenario, dataset, model or run config that fails validation."""


class CliError(BittcError):
    """A bad command line: the message names the flag (raised by ``sim.cli`` only)."""
