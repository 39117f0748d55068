"""The game: what a scenario is, apart from how it is drawn or simulated.

Holds the rules' core (:mod:`~mjmaze.game.core`: ``MazeRules`` and its batched
state), the array kernels the rules share on numpy and torch
(:mod:`~mjmaze.game.arrays`), the mazes (:mod:`~mjmaze.game.maze`,
:mod:`~mjmaze.game.configs`, the released layouts in
:mod:`~mjmaze.game.layouts`) and their walls as boxes (:mod:`~mjmaze.game.wall_boxes`), Doom's constants (:mod:`~mjmaze.game.doom`), the
registry of scenarios and their versioned ids.

May import: nothing of mjmaze outside this folder (``mjmaze.files`` aside).
"""
