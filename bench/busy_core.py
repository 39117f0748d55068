"""The tools that run the network, with another process holding one core.

    python bench/busy_core.py [--rounds 3]

A 2-core box where a training run (or anything) holds a core is the common
case. PyTorch's default is one CPU thread per core; with one of them taken, its
threads wait on each other for the whole time slice of the busy process. Times,
in the same run and alternating the sides round by round:
  evaluate  ``evaluate.evaluate(run, num_envs=4, num_configs=4)``
  record    ``python -m mjmaze.train.record run --episodes 1 --max-steps 500``
each with PyTorch's default threads and with ``--torch-threads 1`` (the tools' default),
while one spinning process holds a core. The run is a fresh one (an untrained
network costs what a trained one does). Prints the median seconds of each side.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time


def _spin() -> None:
    while True:
        pass


def _time(command: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    cores = len(os.sched_getaffinity(0))
    python = sys.executable
    with tempfile.TemporaryDirectory() as folder:
        run = pathlib.Path(folder) / "run"
        subprocess.run([python, "-m", "mjmaze.train.a2c", "--size", "5", "--total-steps", "256", "--num-envs", "2",
                        "--num-steps", "128", "--runs-dir", folder, "--run-name", "run", "--no-progress"],
                       check=True, stdout=subprocess.DEVNULL)
        evaluate = ("import sys; from mjmaze.train import evaluate; "
                    "evaluate.evaluate(sys.argv[1], num_envs=4, num_configs=4, torch_threads={threads}, "
                    "progress=False, out=sys.argv[2])")
        sides = {}
        for threads, label in ((None, f"default ({cores} threads)"), (1, "--torch-threads 1")):
            sides[f"evaluate, {label}"] = [python, "-c", evaluate.format(threads=threads), str(run),
                                           f"{folder}/eval.json"]
            sides[f"record,   {label}"] = [python, "-m", "mjmaze.train.record", str(run), "--episodes", "1",
                                           "--max-steps", "500", "--out", f"{folder}/episode.mp4",
                                           "--torch-threads", str(threads or cores)]
        busy = mp.get_context("spawn").Process(target=_spin, daemon=True)
        busy.start()
        try:
            times = {name: [] for name in sides}
            for k in range(args.rounds):
                order = list(sides) if k % 2 == 0 else list(reversed(sides))
                for name in order:
                    times[name].append(_time(sides[name]))
        finally:
            busy.kill()
    print(f"{cores} cores, one held by a spinning process; median of {args.rounds} rounds, seconds:")
    for name, values in times.items():
        print(f"  {name:40s} {statistics.median(values):7.1f}   ({', '.join(f'{v:.1f}' for v in values)})")


if __name__ == "__main__":
    main()
