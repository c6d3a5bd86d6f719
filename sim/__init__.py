"""The simulated world: PyBullet camera, exact ground truth, highway-env traffic.

Importing this package registers the Gymnasium environment ``bittc/Scenario-v0``.
"""

from gymnasium.envs.registration import register, registry

if "bittc/Scenario-v0" not in registry:
    register(id="bittc/Scenario-v0", entry_point="sim.env:ScenarioEnv")
