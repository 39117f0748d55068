"""The look: how a frame is drawn and lit, on the CPU (GL) or the GPU (MuJoCo Warp's rays).

Holds the view and the frame pipeline (:mod:`~mjmaze.drawing.look`: ``View``,
``FramePipeline``, Doom's light, sprites, flashes, head-bob, the pistol), the
GL renderers (:mod:`~mjmaze.drawing.render`) and Doom's light compiled with
numba (:mod:`~mjmaze.drawing.compiled_light`).

May import: :mod:`mjmaze.game`, :mod:`mjmaze.build`.
"""
