"""The baseline without any intervention."""

from __future__ import annotations

from controllers.base import BrakeCommand, Controller, Observation


class NoController(Controller):
    """Never warns, never brakes: shows the unmitigated outcome of a scenario."""

    name = "none"

    def act(self, obs: Observation, truth) -> BrakeCommand:
        return BrakeCommand()
