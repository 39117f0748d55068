"""Success on the training and test mazes at every kept checkpoint of a run.

    python -m train.a2c --scenario labyrinth --size 5 --total-steps 4000000 \\
        --checkpoint-every 500000 --keep-checkpoints 20 --run-name lab5
    python bench/learning_curve.py runs/lab5

Evaluates each checkpoint greedily (train.evaluate: 64 configurations x 2 per
split), prints the curve as a table and writes ``curve.json`` into the run.
"""

from __future__ import annotations

import argparse
import pathlib

from train import checkpoint, evaluate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir", type=pathlib.Path)
    parser.add_argument("--num-envs", type=int, default=16)
    args = parser.parse_args()
    rows = []
    for path in checkpoint.checkpoints(args.run_dir / "checkpoints"):
        result = evaluate.evaluate(args.run_dir, path, num_envs=args.num_envs)
        rows.append({"step": result["step"], "train": result["train"]["value"], "test": result["test"]["value"],
                     "units": result["units"]})
        print(f"  step {result['step']:>11,}: train {result['train']['value']:6.1f}  test {result['test']['value']:6.1f}"
              f"  ({result['units']})", flush=True)
    checkpoint.atomic_write_json(args.run_dir / "curve.json", rows)
    print(f"written: {args.run_dir / 'curve.json'}")


if __name__ == "__main__":
    main()
