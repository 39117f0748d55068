"""What the paper published of each scenario, and how mjmaze's tables and plots show it.

An env needs none of this (:class:`mjmaze.game.registry.Scenario` holds what it
needs); the reports (:mod:`mjmaze.train.report`, :mod:`mjmaze.train.paper_table`),
the curves (:mod:`mjmaze.train.curves`), the sweep's grid (:mod:`mjmaze.train.sweep`)
and the analysis (:mod:`mjmaze.train.analysis`) read it here. A scenario the paper
did not have gets :class:`Published`'s defaults: no Table 2, no curves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from mjmaze.game import registry

#: Agent steps at which the paper's curves were read (its plots' 10M, 20M, 40M,
#: 100M, 200M and 800M frames).
PAPER_CURVE_STEPS = (2_500_000, 5_000_000, 10_000_000, 25_000_000, 50_000_000, 200_000_000)


def paper_curve(values: tuple[float, ...]) -> tuple[tuple[int, float], ...]:
    """``((agent steps, value), ...)`` from values read at :data:`PAPER_CURVE_STEPS`."""
    if len(values) != len(PAPER_CURVE_STEPS):
        raise ValueError(f"a paper curve has {len(PAPER_CURVE_STEPS)} values, got {len(values)}")
    return tuple(zip(PAPER_CURVE_STEPS, values))


@dataclasses.dataclass(frozen=True)
class Published:
    """One scenario's published numbers and how to show its metric.

    Attributes:
      difficulties: the values of the paper's Table 2 (what the sweep trains).
      results: difficulty -> (train mean, train std, test mean, test std) of Table 2 (200M steps, 3 seeds).
      curves: difficulty -> ``((agent steps, value), ...)``: the paper's training curve (A2C, mean of 3
        seeds), read by eye off the plots released with its implementation
        (edbeeching/3D_Control_RL_Scenario_Benchmarks, ``results/``; their x axis counts frames, 4 per
        agent step): :func:`paper_curve`.
      curve_field: the ``info`` field those curves plot (``""``: the scenario's metric).
      curve_scale: factor from that field's mean to the curves' units (None: the metric's scale).
      curve_units: the curves' units (``""``: the metric's units).
      metric_digits: decimals to print the metric with.
      landmark: what the analysis marks the first sighting of (object 0; ``""``: its name).
    """

    difficulties: tuple[int, ...] = ()
    results: Mapping[int, tuple[float, float, float, float]] = dataclasses.field(default_factory=dict)
    curves: Mapping[int, tuple[tuple[int, float], ...]] = dataclasses.field(default_factory=dict)
    curve_field: str = ""
    curve_scale: float | None = None
    curve_units: str = ""
    metric_digits: int = 1
    landmark: str = ""


PUBLISHED = {
    "labyrinth": Published(
        difficulties=(7, 9, 11, 13),
        results={7: (99.8, 0.2, 99.5, 0.2), 9: (98.1, 0.8, 97.4, 1.3), 11: (95.2, 0.7, 90.1, 1.0),
                 13: (84.1, 1.8, 79.8, 1.9)},
        # Training success %, read off the released plots.
        curves={
            7: paper_curve((40, 65, 80, 90, 97, 99)),
            9: paper_curve((25, 45, 70, 80, 88, 95)),
            11: paper_curve((10, 25, 45, 70, 80, 88)),
            13: paper_curve((5, 15, 40, 60, 70, 77)),
        },
        landmark="exit",
    ),
    "find_return": Published(
        difficulties=(7, 9, 11, 13),
        results={7: (98.7, 0.3, 95.1, 0.2), 9: (87.0, 1.9, 81.6, 1.8), 11: (70.9, 1.6, 64.0, 1.6),
                 13: (57.7, 0.8, 52.9, 3.7)},
        # Training success %, read off the released plots.
        curves={
            5: paper_curve((35, 58, 75, 85, 93, 96)),
            7: paper_curve((30, 50, 63, 72, 82, 94)),
            9: paper_curve((15, 30, 45, 55, 60, 81)),
        },
        landmark="red pillar",
    ),
    "k_item": Published(
        difficulties=(2, 4, 6, 8),
        results={2: (0.968, 0.004, 0.932, 0.012), 4: (0.910, 0.012, 0.861, 0.015),
                 6: (0.577, 0.024, 0.522, 0.023), 8: (0.084, 0.071, 0.083, 0.070)},
        # The released plots show the return over its most (K x 0.5), not items in order / K.
        curves={
            2: paper_curve((-0.2, -0.2, 0.05, 0.3, 0.78, 0.92)),
            4: paper_curve((-0.1, -0.1, -0.05, 0.05, 0.1, 0.86)),
        },
        curve_field="normalised_return",
        curve_scale=1.0,
        curve_units="return / (K x 0.5)",
        metric_digits=3,
        landmark="first item",
    ),
    "two_colour": Published(
        difficulties=(1, 3, 5, 7),
        results={1: (1903, 27, 1941, 4), 3: (1789, 24, 1781, 24), 5: (1436, 158, 1432, 161),
                 7: (1159, 126, 1128, 140)},
        # Tics survived in training episodes, read off the released plots.
        curves={
            1: paper_curve((430, 530, 700, 850, 1100, 1920)),
            3: paper_curve((430, 530, 720, 1000, 1100, 1750)),
            7: paper_curve((410, 470, 650, 780, 900, 1100)),
        },
        metric_digits=0,
        landmark="totem",
    ),
}


def of(name: str) -> Published:
    """Scenario ``name``'s published numbers (none for a scenario the paper did not have; an unknown
    name is the registry's ``ValueError``)."""
    registry.get(name)
    return PUBLISHED.get(name, Published())


def curve_field(name: str) -> str:
    """The ``info`` field the paper's curves of scenario ``name`` plot."""
    return of(name).curve_field or registry.get(name).metric


def curve_scale(name: str) -> float:
    """Factor from :func:`curve_field`'s mean to the curves' units."""
    scale = of(name).curve_scale
    return registry.get(name).metric_scale if scale is None else scale


def curve_units(name: str) -> str:
    return of(name).curve_units or registry.get(name).metric_units


def landmark(name: str) -> str:
    """What the analysis marks the first sighting of: the scenario's object 0."""
    return of(name).landmark or registry.get(name).rules.objects[0].name
