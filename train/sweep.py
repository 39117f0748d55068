"""The paper's experiment grid on Ray: one training run per (scenario, difficulty, seed), each then evaluated.

    python -m mjmaze.train.sweep --grid small --total-steps 1000000     # Labyrinth 5 and 7 x 2 seeds
    python -m mjmaze.train.sweep --grid paper                           # Table 2: 4 scenarios x 4 difficulties x 3 seeds, 200M steps
    python -m mjmaze.train.sweep --grid generalisation                  # Labyrinth 9 with 16/64/256/1024 training mazes x 3 seeds
    python -m mjmaze.train.sweep --grid evidence                        # learning curves beside the paper's: 4 settings x 2 seeds, 5-10M steps
    python -m mjmaze.train.sweep --grid custom --scenario k_item --difficulties 2 4 --seeds 0 1
    python -m mjmaze.train.sweep --grid paper --address auto --cpus-per-run 4 --gpus-per-run 0.25   # an existing cluster
    python -m mjmaze.train.report sweeps/paper                          # the table and curves

Each run is a Ray task (local Ray by default; ``--address`` joins a cluster,
whose nodes need mjmaze installed and a shared ``--sweeps-dir``) holding
``--cpus-per-run`` CPUs (the training process and its env workers) and ``--gpus-per-run`` of a GPU.
Everything lands in ``sweeps/<name>/``: ``sweep.json`` (the grid and flags) and
one run folder per run, laid out as ``mjmaze.train.a2c`` does, with ``eval.json``
(``mjmaze.train.evaluate``) written as the run ends.

**Resumable**: run the same command again. A run whose ``eval.json`` covers
the full ``--total-steps`` is never redone; a crashed or killed one goes on from
its last checkpoint (lines it logged after that checkpoint are dropped); a run
that never checkpointed starts over. Ray retries a task whose worker died
(``--retries``), from its checkpoint too.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import sys
import time

from tqdm import tqdm

from mjmaze import files
from mjmaze.backends import suite
from mjmaze.game import registry

from . import a2c, checkpoint, evaluate, published
from .settings import Args

GENERALISATION_CONFIGS = (16, 64, 256, 1024)
# The generalisation study's maze size: the paper does not state it; Labyrinth's default.
GENERALISATION_SIZE = 9
# The settings whose curves the paper's released plots show rising early
# (../paper/CURVES.md), each with the agent steps a 2-core machine can afford:
# K-item and Two-colour rise only after ~5M observations.
EVIDENCE = (("labyrinth", 7, 5_000_000), ("find_return", 5, 5_000_000), ("k_item", 2, 10_000_000),
            ("two_colour", 1, 10_000_000))
# Enough to keep every checkpoint of the longest run (a greedy evaluation of each draws the curve).
KEEP_EVERY_CHECKPOINT = 1000
GRIDS = ("paper", "generalisation", "small", "evidence", "custom")
DEFAULT_STEPS = {"paper": 200_000_000, "generalisation": 200_000_000, "small": 1_000_000, "evidence": 5_000_000,
                 "custom": 10_000_000}


@dataclasses.dataclass(frozen=True)
class RunSpec:
    """One run of a grid."""

    scenario: str
    difficulty: int
    seed: int
    num_configs: int | None = None
    #: This run's length in agent steps (None: the sweep's ``--total-steps``).
    total_steps: int | None = None

    @property
    def name(self) -> str:
        configs = f"_n{self.num_configs}" if self.num_configs else ""
        return f"{self.scenario}_{registry.get(self.scenario).difficulty}{self.difficulty}{configs}_s{self.seed}"

    def args(self, settings: dict, runs_dir: pathlib.Path) -> Args:
        """The training flags of this run: ``settings`` (shared by the sweep) plus its own."""
        return Args(**{
            **settings, **({"total_steps": self.total_steps} if self.total_steps else {}), "scenario": self.scenario, registry.get(self.scenario).difficulty: self.difficulty, "seed": self.seed,
            "num_configs": self.num_configs, "runs_dir": str(runs_dir), "run_name": self.name, "progress": False,
        })


def grid(name: str, seeds: list[int] | None = None, scenario: str | None = None,
         difficulties: list[int] | None = None, num_configs: list[int] | None = None) -> list[RunSpec]:
    """The runs of grid ``name``; ``seeds`` overrides the grid's, the rest define ``custom``."""
    if name == "paper":
        seeds = seeds or [0, 1, 2]
        return [
            RunSpec(scenario, d, seed)
            for scenario in suite.ALL_TASKS
            for d in published.of(scenario).difficulties
            for seed in seeds
        ]
    if name == "generalisation":
        seeds = seeds or [0, 1, 2]
        return [RunSpec("labyrinth", GENERALISATION_SIZE, seed, n) for n in GENERALISATION_CONFIGS for seed in seeds]
    if name == "small":
        seeds = seeds or [0, 1]
        return [RunSpec("labyrinth", d, seed) for d in (5, 7) for seed in seeds]
    if name == "evidence":  # every setting's first seed before any second one
        seeds = seeds or [0, 1]
        return [RunSpec(scenario, d, seed, total_steps=steps) for seed in seeds for scenario, d, steps in EVIDENCE]
    if name == "custom":
        if scenario not in registry.names() or not difficulties:
            raise ValueError(f"--grid custom needs --scenario (one of {registry.names()}) and --difficulties")
        seeds = seeds or [0]
        return [RunSpec(scenario, d, seed, n) for d in difficulties for n in (num_configs or [None]) for seed in seeds]
    raise ValueError(f"unknown grid {name!r}; choose one of {GRIDS}")


def finished(run_dir: pathlib.Path, total_steps: int) -> dict | None:
    """The run's evaluation if it covers ``total_steps``, else None."""
    try:
        result = json.loads((run_dir / "eval.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None
    return result if result.get("step", 0) >= total_steps else None


def check_same_run(run_dir: pathlib.Path, config: dict) -> None:
    """Raises ValueError if ``run_dir`` holds a run trained with other settings than ``config``.

    A sweep resumes or skips the runs it finds; one saved with other
    settings (e.g. without head-bob) would be resumed or reported as this one.
    """
    try:
        saved = json.loads((run_dir / "config.json").read_text())
    except FileNotFoundError:
        return
    differ = checkpoint.identity_differences(saved, config)
    if differ:
        detail = ", ".join(f"{k}: saved {a!r} vs now {b!r}" for k, (a, b) in differ.items())
        go_on = f"pass {checkpoint.flags(saved, ['eps'])} to go on with it, " if set(differ) == {"eps"} else ""
        raise ValueError(f"{run_dir} holds a run with other settings ({detail}); {go_on}"
                         "move it aside (nothing was changed) or pass --name for a new sweep folder")


def run_one(spec: RunSpec, settings: dict, sweep_dir: str, eval_envs: int, eval_configs: int) -> dict:
    """Trains (or resumes) one run, then evaluates it; what a Ray task runs."""
    args = spec.args(settings, pathlib.Path(sweep_dir))
    run_dir = pathlib.Path(sweep_dir) / spec.name
    done = finished(run_dir, args.total_steps)
    if done is not None:
        return {"name": spec.name, "status": "already finished", "eval": done}
    found = checkpoint.checkpoints(run_dir / "checkpoints")
    resumed_from = checkpoint.load(found[-1], dataclasses.asdict(args))["step"] if found else 0
    if resumed_from < args.total_steps:
        a2c.train(dataclasses.replace(args, resume=bool(found)))
    result = evaluate.evaluate(run_dir, num_envs=eval_envs, num_configs=eval_configs)
    status = f"resumed from step {resumed_from:,}" if found else "trained"
    return {"name": spec.name, "status": status, "eval": result}


def launch(specs: list[RunSpec], sweep_dir: pathlib.Path, settings: dict, *, address: str | None = None,
           num_cpus: int | None = None, cpus_per_run: int = 2, gpus_per_run: float = 0.0, retries: int = 1,
           eval_envs: int = 16, eval_configs: int = evaluate.EVAL_CONFIGS, log=tqdm.write) -> list[dict]:
    """Runs ``specs`` on Ray (skipping finished runs); returns one result per run, finished ones included."""
    import ray

    evaluate.check_sizes(eval_envs, eval_configs)  # a run's evaluation comes only after its training

    sweep_dir = pathlib.Path(sweep_dir).resolve()  # Ray workers do not share the driver's working directory
    results, todo = [], []
    for spec in specs:
        done = finished(sweep_dir / spec.name, spec.total_steps or settings["total_steps"])
        if done is not None:
            results.append({"name": spec.name, "status": "already finished", "eval": done})
            log(f"[sweep] {spec.name}: already finished (step {done['step']:,}), skipped")
        else:
            todo.append(spec)
    if not todo:
        return results
    if address is None:
        ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False, configure_logging=False)
    else:
        ray.init(address=address, log_to_driver=False, configure_logging=False)
    try:
        # A run asking for more than the cluster has would wait forever: say so now.
        have = ray.cluster_resources()
        for flag, asked, kind in (("--cpus-per-run", cpus_per_run, "CPU"), ("--gpus-per-run", gpus_per_run, "GPU")):
            if asked > have.get(kind, 0):
                raise ValueError(f"{flag} {asked} is more than the {have.get(kind, 0):g} {kind}(s) Ray has: "
                                 "no run could start")
        remote = ray.remote(num_cpus=cpus_per_run, num_gpus=gpus_per_run, max_retries=retries)(run_one)
        pending = {remote.remote(spec, settings, str(sweep_dir), eval_envs, eval_configs): spec for spec in todo}
        log(f"[sweep] {len(todo)} run(s) submitted, {len(results)} already finished; {sweep_dir}")
        start = time.monotonic()
        bar = tqdm(total=len(todo), desc="runs", unit="run", disable=None, dynamic_ncols=True)
        while pending:
            (ready,), _ = ray.wait(list(pending), num_returns=1)
            spec = pending.pop(ready)
            try:
                result = ray.get(ready)
            except Exception as error:  # one failed run must not stop the others
                cause = getattr(error, "cause", None) or error  # a RayTaskError wraps the run's own exception
                result = {"name": spec.name, "status": f"failed: {type(cause).__name__}: {cause}".splitlines()[0]}
                log(f"[sweep] {spec.name}: {result['status']}")
            else:
                e = result["eval"]
                log(f"[sweep] {spec.name}: {result['status']}; {e['units']} train {e['train']['value']:.3g} "
                    f"test {e['test']['value']:.3g} ({time.monotonic() - start:.0f} s, {len(pending)} left)")
            results.append(result)
            bar.update()
        bar.close()
    finally:
        ray.shutdown()
    return results


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--grid", default="small", choices=GRIDS)
    parser.add_argument("--name", default=None, help="the sweep's folder under --sweeps-dir (default: the grid's name)")
    parser.add_argument("--sweeps-dir", type=pathlib.Path, default=pathlib.Path("sweeps"))
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="default: 0 1 2 (paper), 0 1 (small)")
    parser.add_argument("--scenario", default=None, help="--grid custom: the scenario")
    parser.add_argument("--difficulties", type=int, nargs="+", default=None, help="--grid custom: sizes, K or c")
    parser.add_argument("--num-configs", type=int, nargs="+", default=None, help="--grid custom: training set sizes")
    parser.add_argument("--only", nargs="+", default=None, metavar="RUN",
                        help="run only these runs of the grid, in this order (their folder names, e.g. "
                             "k_item_num_items2_s0)")
    parser.add_argument("--total-steps", type=int, default=None,
                        help=f"agent steps per run (default: {DEFAULT_STEPS})")
    parser.add_argument("--num-envs", type=int, default=Args.num_envs)
    parser.add_argument("--num-steps", type=int, default=Args.num_steps)
    parser.add_argument("--eps", type=float, default=Args.eps,
                        help="RMSprop epsilon (1e-8: the released learner's)")
    parser.add_argument("--checkpoint-every", type=int, default=None, help="default: total steps / 20")
    parser.add_argument("--keep-checkpoints", type=int, default=None,
                        help="checkpoints kept per run (default: every one for --grid evidence, whose curves "
                             "evaluate each, else 3)")
    parser.add_argument("--device", default="auto", help="auto (CUDA where Ray gives the task a GPU), cpu, cuda")
    parser.add_argument("--address", default=None, help="an existing Ray cluster ('auto' or host:port)")
    parser.add_argument("--num-cpus", type=int, default=None, help="local Ray: CPUs to use (default: all)")
    parser.add_argument("--cpus-per-run", type=int, default=2, help="CPUs per run (the training process and its env workers, at least 1)")
    parser.add_argument("--gpus-per-run", type=float, default=0.0, help="fraction of a GPU per run")
    parser.add_argument("--retries", type=int, default=1, help="Ray retries of a run whose worker died")
    parser.add_argument("--eval-envs", type=int, default=16, help="parallel envs for the evaluation")
    parser.add_argument("--eval-configs", type=int, default=evaluate.EVAL_CONFIGS,
                        help="configurations per split in the evaluation, each played twice (paper: 64)")
    args = parser.parse_args(argv)
    try:
        specs = grid(args.grid, args.seeds, args.scenario, args.difficulties, args.num_configs)
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    if args.only:
        unknown = sorted(set(args.only) - {spec.name for spec in specs})
        if unknown:
            raise SystemExit(f"error: --only {unknown}: not runs of --grid {args.grid}; its runs: "
                             f"{[spec.name for spec in specs]}")
        by_name = {spec.name: spec for spec in specs}
        specs = [by_name[name] for name in dict.fromkeys(args.only)]  # the order asked for, each once
    if args.total_steps:  # one length for every run, the grid's own lengths overridden
        specs = [dataclasses.replace(spec, total_steps=None) for spec in specs]
    total_steps = args.total_steps or DEFAULT_STEPS[args.grid]
    settings = {
        "total_steps": total_steps, "num_envs": args.num_envs, "num_steps": args.num_steps, "eps": args.eps,
        "device": args.device,
        "checkpoint_every": args.checkpoint_every or max(args.num_envs * args.num_steps, total_steps // 20),
        "keep_checkpoints": args.keep_checkpoints or (KEEP_EVERY_CHECKPOINT if args.grid == "evidence" else Args.keep_checkpoints),
        # The training process steps a share of the envs itself: one worker fewer than the run's CPUs.
        "num_workers": args.cpus_per_run - 1, "torch_threads": args.cpus_per_run,
    }
    sweep_dir = args.sweeps_dir / (args.name or args.grid)
    try:
        # Every flag and every run's settings are valid before anything starts:
        # a bad one would otherwise fail only after hours of training.
        if args.cpus_per_run < 1 or args.gpus_per_run < 0 or args.retries < 0:
            raise ValueError("--cpus-per-run must be at least 1, --gpus-per-run and --retries at least 0")
        evaluate.check_sizes(args.eval_envs, args.eval_configs)
        for spec in specs:
            run_args = spec.args(settings, args.sweeps_dir)
            run_args.validate()
            check_same_run(sweep_dir / spec.name, dataclasses.asdict(run_args))
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    files.atomic_write_json(sweep_dir / "sweep.json", {
        "grid": args.grid, "runs": [s.name for s in specs], "settings": settings, "command": sys.argv,
        "run_steps": {s.name: s.total_steps or total_steps for s in specs},
        "eval_configs": args.eval_configs,
    })
    try:
        results = launch(specs, sweep_dir, settings, address=args.address, num_cpus=args.num_cpus,
                         cpus_per_run=args.cpus_per_run, gpus_per_run=args.gpus_per_run, retries=args.retries,
                         eval_envs=args.eval_envs, eval_configs=args.eval_configs)
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    failed = [r for r in results if r["status"].startswith("failed")]
    print(f"[sweep] {len(results) - len(failed)}/{len(results)} runs finished in {sweep_dir}; "
          f"table: python -m mjmaze.train.report {sweep_dir}")
    if failed:
        raise SystemExit(f"error: {len(failed)} run(s) failed: {', '.join(r['name'] for r in failed)}; "
                         "run the same command again to resume them")


if __name__ == "__main__":
    main()
