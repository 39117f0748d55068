"""The paper's own trainer, runnable today: a patched copy of the released `3dcdrl/`, and its command.

    python tools/released_trainer.py CHECKOUT OUT          # copies CHECKOUT/3dcdrl to OUT, patched
    python tools/released_trainer.py CHECKOUT OUT --print two_colour 1   # and the training command

CHECKOUT is a checkout of github.com/edbeeching/3d_control_deep_rl (MIT). The copy
is patched only where today's libraries need it, never the algorithm, its
settings, the rewards, the env or the evaluation (docs/notes/learning.md, "The
released trainer"):

- ``scorer.py`` imports moviepy (not a dependency; moviepy 2 has no
  ``moviepy.editor``) at the top, for evaluation videos the trainer never asks
  for: imported where a video is written;
- ``doom_environment.py`` sets no game data, so ViZDoom 1.3.2 would play its own
  Freedoom 0.13: the paper's 0.10.1 (``$DOOM_IWAD``, which the printed command sets
  to :func:`mjmaze.backends.vizdoom_env.paper_freedoom`);
- ``a2c_agent.py``'s ``torch.load`` of a checkpoint holding an argparse namespace:
  ``weights_only=False``, as torch before 2.6 loaded it (``--reload_model``).

Kept as released: ``cv2.resize(obs, size, cv2.INTER_AREA)`` (bilinear: the flag
is OpenCV's ``dst``). Its ``--num_frames`` counts agent steps; evaluations (128
greedy test games) every 1000 updates (2.05M steps) go to the log's
``Eval mean reward`` and ``Game times`` lines, which
``python -m mjmaze.train.engines add-released SETTING LOG`` puts beside both
engines' curves.
"""

from __future__ import annotations

import argparse
import pathlib
import shutil
import sys

# (file, released text, patched text): each released text occurs once.
PATCHES = (
    ("scorer.py", "from moviepy.editor import ImageSequenceClip\n",
     "# patched: moviepy is imported in write_movie, the one place that needs it\n"),
    ("scorer.py", "def write_movie(output_dir, observations, step, score, best_agent=True):    \n",
     "def write_movie(output_dir, observations, step, score, best_agent=True):    \n"
     "    from moviepy.editor import ImageSequenceClip  # patched: imported where used\n"),
    ("doom_environment.py", "\nimport math\n", "\nimport math, os  # patched: os for DOOM_IWAD\n"),
    ("doom_environment.py", "        game.init() \n",
     "        game.set_doom_game_path(os.environ['DOOM_IWAD'])  # patched: the paper's Freedoom 0.10.1\n"
     "        game.init() \n"),
    ("a2c_agent.py", "checkpoint = torch.load(checkpoint_filename)\n",
     "checkpoint = torch.load(checkpoint_filename, weights_only=False)  # patched: torch>=2.6\n"),
    ("a2c_agent.py", "checkpoint = torch.load(checkpoint_filename, map_location=lambda storage, loc: storage)\n",
     "checkpoint = torch.load(checkpoint_filename, map_location=lambda storage, loc: storage, "
     "weights_only=False)  # patched: torch>=2.6\n"),
)

#: The released README's training command, for one setting's train and test folders.
COMMAND = ("OMP_NUM_THREADS=1 DOOM_IWAD={iwad} python {out}/train_agent.py --scenario 'custom_scenario{{:003}}.cfg' "
           "--limit_actions --scenario_dir {scenarios}/{folder}/{difficulty}/train/ "
           "--test_scenario_dir {scenarios}/{folder}/{difficulty}/test/ --multimaze --num_mazes_train 256 "
           "--num_mazes_test 64 --fixed_scenario --num_frames {steps} --out_dir {out}/runs/ --job_id 1 "
           "--test_name {folder}_{difficulty}.sh")


def patched_copy(checkout: pathlib.Path, out: pathlib.Path) -> None:
    """Copies ``checkout/3dcdrl`` to ``out`` and applies :data:`PATCHES` (``out`` must not exist)."""
    source = checkout / "3dcdrl"
    if not (source / "train_agent.py").is_file():
        raise SystemExit(f"error: {checkout} is no checkout of edbeeching/3d_control_deep_rl (no 3dcdrl/train_agent.py)")
    if out.exists():
        raise SystemExit(f"error: {out} exists: give a new folder (a patched copy is never overwritten)")
    shutil.copytree(source, out)
    for name, released, patched in PATCHES:
        path = out / name
        text = path.read_text()
        if text.count(released) != 1:
            shutil.rmtree(out)
            raise SystemExit(f"error: {name} is not the released file (its patch does not apply): another commit?")
        path.write_text(text.replace(released, patched))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkout", type=pathlib.Path)
    parser.add_argument("out", type=pathlib.Path)
    parser.add_argument("--print", nargs=2, metavar=("SCENARIO", "DIFFICULTY"), default=None,
                        help="also print the training command for this setting (e.g. two_colour 1)")
    parser.add_argument("--steps", type=int, default=10_000_000, help="agent steps (--num_frames), default 10M")
    args = parser.parse_args(argv)
    patched_copy(args.checkout, args.out)
    print(f"patched copy: {args.out}")
    if args.print:
        from mjmaze.backends import vizdoom_env

        scenario, difficulty = args.print
        print(COMMAND.format(iwad=vizdoom_env.paper_freedoom(), out=args.out.resolve(),
                             scenarios=(args.out / "scenarios" / "custom_scenarios").resolve(),
                             folder=vizdoom_env.RELEASED_FOLDERS[scenario], difficulty=int(difficulty),
                             steps=args.steps))


if __name__ == "__main__":
    main(sys.argv[1:])
