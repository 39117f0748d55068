"""The arena's build: a scenario's MJCF written once, and each compiled model made final.

Holds the builder (:mod:`~mjmaze.build.arena`: ``Arena``, ``ArenaIds``), the
MJCF writer (:mod:`~mjmaze.build.mjcf`), the walls' collision pool and meshes
(:mod:`~mjmaze.build.walls`), Freedoom's pictures (:mod:`~mjmaze.build.sprites`)
and Doom's colours and rooms (:mod:`~mjmaze.build.palette`).

May import: :mod:`mjmaze.game`.
"""
