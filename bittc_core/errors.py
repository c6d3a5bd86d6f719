"""Errors that carry a message meant for the user."""


class CliError(Exception):
    """A bad input or an impossible request: the message names the bad value."""


class ConfigError(CliError, ValueError):
    """A scenario, dataset or model config that fails validation."""
