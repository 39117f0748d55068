"""The scenarios: one module each, declaring its rules (a ``MazeRules`` subclass), its arena's objects
and room, and its ``SCENARIO`` (:class:`mjmaze.game.registry.Scenario`), which
:mod:`mjmaze.backends.suite` collects. A fifth scenario is one more module here.

May import: :mod:`mjmaze.game`, :mod:`mjmaze.build`, :mod:`mjmaze.drawing`.
"""
