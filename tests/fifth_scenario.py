"""A fifth scenario, stated once, here: registering it (tests/conftest.py does, for every test) is all
it takes for load, gymnasium, the vector env, check_env, MuJoCo Warp and the rules on torch: every
test that runs "every scenario" reads the registry and so runs this one too.
"""

from __future__ import annotations

from mjmaze.build import mjcf
from mjmaze.game import configs, core, maze, registry, arrays

GOAL = mjcf.ObjectGeom("goal", "sphere", (0.15,), (1.0, 0.9, 0.0, 1.0), 0.3)


class Beacon(core.MazeRules):
    """Reach the yellow beacon of a small maze: +1, and the episode ends."""

    scenario = "beacon"
    objects = (GOAL,)

    def __init__(self, size: int = 3, **kwargs):
        core.check_choice("size", size, (3, 4))
        layout = configs.LayoutSpec(size, 1.0, maze.DEFAULT_KEEP_PROBABILITY, num_objects=1)
        super().__init__(difficulty=size, layout=layout, **kwargs)

    def start(self, xp, config, keys):
        batch, device = keys.shape[0], arrays.device(keys)
        return {
            "pose": xp.concat([config["spawn_xy"], self.spawn_yaw(xp, keys)[:, None]], axis=1),
            "object_xy": config["object_xy"],
            "object_shown": xp.ones((batch, 1), dtype=xp.bool, device=device),
            "reached": xp.zeros(batch, dtype=xp.bool, device=device),
        }

    def rules(self, xp, state, path):
        state["reached"] = arrays.touched(xp, state["object_xy"][:, 0], path)
        return xp.astype(state["reached"], xp.float64), state["reached"]

    def episode_metrics(self, state):
        return {"reached": state["reached"]}


SCENARIO = registry.Scenario(
    name="beacon", rules=Beacon, gym_id="mjmaze_test/Beacon-v0", seed_code=1001, difficulty="size",
    difficulties=(3, 4), metric="reached", metric_scale=100.0, metric_units="reached %", cell_size=1.0,
)
