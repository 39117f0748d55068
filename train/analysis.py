"""Hidden-state analysis, as in the paper's Fig. 1 and Fig. 7.

    python -m mjmaze.train.analysis runs/two_colour_5_s0 --episodes 20
    python -m mjmaze.train.analysis random --scenario two_colour --complexity 5 --episodes 4 --max-steps 100

Plays ``--episodes`` episodes (greedy; ``--sample`` to sample) on the test
configurations, records the GRU state after every frame, and writes into
``--out`` (default ``<run>/analysis``):

- ``states.npz``: every recorded state with its episode, step, pose, and, per
  episode, the step at which the landmark (Two-colour's totem, Labyrinth's exit,
  Find-and-return's red pillar, K-item's first item) first came into view;
- ``heatmap.png``: the 128 activations of one episode (``--heatmap-episode``,
  default the longest) over time, that step marked;
- ``tsne.png`` and ``tsne.npz``: a t-SNE (scikit-learn) of up to
  ``--tsne-states`` states drawn evenly from all episodes, coloured by time step,
  with up to 20 episodes drawn as lines; for Two-colour a second panel coloured
  by the totem's colour;
- ``summary.json``: what was played and written; for Two-colour also
  ``totem_probe``: how well a linear read-out (scikit-learn's logistic
  regression, cross-validated across episodes) tells the totem's colour from
  the GRU state once the totem has been seen, beside the majority colour's
  share. The policy can only act on the colour if its state carries it; the
  ``random`` agent's untrained network gives the baseline.

``random`` analyses an untrained agent acting uniformly at random: the baseline
against which a trained agent's structure stands out.
"""

from __future__ import annotations

import argparse
import io
import pathlib

import numpy as np
from matplotlib.figure import Figure

import mjmaze
from mjmaze import files
from mjmaze.backends import suite

from . import checkpoint, policy, published
from .settings import using_torch_threads

TSNE_STATES = 2000
TSNE_LINES = 20
PROBE_FOLDS = 5


def record_states(source_args: argparse.Namespace, episodes: int, max_steps: int | None = None):
    """Plays the episodes; returns ``(scenario, task kwargs, description, episodes)``."""
    scenario, task_kwargs, agent_policy, description = policy.policy_from_arguments(source_args)
    env = mjmaze.load(scenario, task_kwargs={**task_kwargs, "split": source_args.split, "random": source_args.seed})
    try:
        with using_torch_threads(policy.threads_of(source_args)):
            played = policy.play_episodes(env, agent_policy, episodes, max_steps=max_steps, progress=True)
    finally:
        env.task.close()
    return scenario, task_kwargs, description, played


def save_figure(figure: Figure, path: pathlib.Path) -> pathlib.Path:
    """Saves a matplotlib figure as a PNG, atomically."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    files.atomic_write_bytes(path, buffer.getvalue())
    return path


def heatmap(episode: policy.Episode, scenario: str, title: str) -> Figure:
    """Activations of one episode over time, the landmark's first sighting marked."""
    figure = Figure(figsize=(10, 4))
    axes = figure.subplots()
    # A GRU unit lies in (-1, 1), but a trained agent's often stay within +-0.1: a +-1 scale drew them
    # blank. The scale is the episode's own (99th percentile of |h|), symmetric so that white is 0.
    scale = max(float(np.percentile(np.abs(episode.hidden), 99)), 1e-3)
    image = axes.imshow(episode.hidden.T, aspect="auto", cmap="RdBu_r", vmin=-scale, vmax=scale, interpolation="nearest")
    seen = episode.landmark_first_seen
    if seen is not None and seen < episode.length:
        axes.axvline(seen, color="k", linestyle="--", linewidth=1.5,
                     label=f"{published.landmark(scenario)} first in view (step {seen})")
        axes.legend(loc="upper right", fontsize=8, framealpha=0.9)
    axes.set_xlabel("step")
    axes.set_ylabel("hidden unit")
    axes.set_title(title, fontsize=10)
    figure.colorbar(image, ax=axes, label=f"activation (colour scale +-{scale:.2g}, the episode's 99th percentile)")
    return figure


def tsne_sample(lengths: list[int], count: int, seed: int) -> np.ndarray:
    """Indices of up to ``count`` states drawn evenly from all episodes, in time order."""
    total = sum(lengths)
    if total <= count:
        return np.arange(total)
    return np.sort(np.random.default_rng(seed).choice(total, size=count, replace=False))


def tsne(states: np.ndarray, seed: int) -> np.ndarray:
    """2-D t-SNE embedding of ``states`` (scikit-learn, PCA initialisation)."""
    from sklearn.manifold import TSNE

    perplexity = float(min(30.0, max(2.0, (len(states) - 1) / 3)))
    return TSNE(n_components=2, perplexity=perplexity, init="pca", random_state=seed).fit_transform(states)


def totem_probe(hidden: np.ndarray, totem_green: np.ndarray, episode_of: np.ndarray, seen: np.ndarray,
                folds: int = PROBE_FOLDS, seed: int = 0) -> dict | None:
    """Cross-validated accuracy of a linear read-out of the totem's colour from the states where ``seen``.

    Folds split by episode (a state is never tested on a read-out fitted to its own
    episode) and keep both colours in each; None when fewer than 2 episodes of
    each colour saw the totem.
    """
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import StratifiedGroupKFold, cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    states, green, groups = hidden[seen], totem_green[seen], episode_of[seen]
    episodes_per_colour = min(len(np.unique(groups[green == colour])) for colour in (False, True))
    if episodes_per_colour < 2:
        return None
    splits = StratifiedGroupKFold(n_splits=min(folds, episodes_per_colour), shuffle=True, random_state=seed)
    read_out = make_pipeline(StandardScaler(), LogisticRegression(max_iter=2000))
    accuracy = cross_val_score(read_out, states, green, groups=groups, cv=splits)
    return {"accuracy": float(accuracy.mean()), "majority": float(max(green.mean(), 1 - green.mean())),
            "states": int(len(states)), "episodes": int(len(np.unique(groups))), "folds": int(len(accuracy))}


def tsne_figure(embedding: np.ndarray, steps: np.ndarray, episode_of: np.ndarray, title: str,
                totem_green: np.ndarray | None = None) -> Figure:
    panels = 1 if totem_green is None else 2
    figure = Figure(figsize=(6.5 * panels, 5.5))
    axes = np.atleast_1d(figure.subplots(1, panels))
    points = axes[0].scatter(embedding[:, 0], embedding[:, 1], c=steps, cmap="viridis", s=6)
    figure.colorbar(points, ax=axes[0], label="time step")
    for e in np.unique(episode_of)[:TSNE_LINES]:
        along = embedding[episode_of == e]
        axes[0].plot(along[:, 0], along[:, 1], color="k", alpha=0.25, linewidth=0.6)
    axes[0].set_title(f"{title}\ncoloured by time step, {min(TSNE_LINES, len(np.unique(episode_of)))} episodes as lines",
                      fontsize=9)
    if totem_green is not None:
        colours = np.where(totem_green, "tab:green", "tab:red")
        axes[1].scatter(embedding[:, 0], embedding[:, 1], c=colours, s=6)
        axes[1].set_title("coloured by the totem's colour", fontsize=9)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    return figure


def analyse(source_args: argparse.Namespace, episodes: int, out: pathlib.Path | None = None,
            tsne_states: int = TSNE_STATES, max_steps: int | None = None, heatmap_episode: int | None = None) -> dict:
    """Records states, writes the files listed in the module docstring; returns the summary."""
    scenario, task_kwargs, description, played = record_states(source_args, episodes, max_steps)
    if out is None:
        out = policy.output_folder(source_args.source) / "analysis" if source_args.source != policy.RANDOM \
            else pathlib.Path("runs") / f"analysis_random_{scenario}"
    played = [e for e in played if e.length > 0]
    if not played:
        raise ValueError("no episode lasted a step: nothing to analyse")
    title = f"{description} | {scenario} {policy.describe(task_kwargs)} | {source_args.split}"
    hidden = np.concatenate([e.hidden for e in played])
    episode_of = np.concatenate([np.full(e.length, k) for k, e in enumerate(played)])
    steps = np.concatenate([np.arange(e.length) for e in played])
    poses = np.concatenate([e.poses[:-1] for e in played])
    first_seen = np.array([-1 if e.landmark_first_seen is None else e.landmark_first_seen for e in played])
    totem_green = None
    if "totem_green" in played[0].infos[0]:  # a totem whose colour is the cue (Two-colour)
        totem_green = np.concatenate([np.full(e.length, bool(e.infos[0]["totem_green"])) for e in played])

    buffer = io.BytesIO()
    np.savez_compressed(buffer, hidden=hidden, episode=episode_of, step=steps, pose=poses,
                        landmark_first_seen=first_seen, **({"totem_green": totem_green} if totem_green is not None else {}))
    files.atomic_write_bytes(out / "states.npz", buffer.getvalue())
    if heatmap_episode is None:  # the longest episode shows the most
        heatmap_episode = int(np.argmax([e.length for e in played]))
    if not 0 <= heatmap_episode < len(played):
        raise ValueError(f"--heatmap-episode must be in 0..{len(played) - 1}, got {heatmap_episode}")
    shown = played[heatmap_episode]
    save_figure(heatmap(shown, scenario, f"episode {heatmap_episode} ({shown.length} steps) - {title}"),
                out / "heatmap.png")

    chosen = tsne_sample([e.length for e in played], tsne_states, source_args.seed)
    embedding = tsne(hidden[chosen], source_args.seed)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, embedding=embedding, state_index=chosen)
    files.atomic_write_bytes(out / "tsne.npz", buffer.getvalue())
    save_figure(tsne_figure(embedding, steps[chosen], episode_of[chosen], title,
                            None if totem_green is None else totem_green[chosen]), out / "tsne.png")

    probe = None
    if totem_green is not None:
        sighting = first_seen[episode_of]  # per state, its episode's first sighting (-1: never)
        seen = (sighting >= 0) & (steps >= sighting)
        probe = totem_probe(hidden, totem_green, episode_of, seen, seed=source_args.seed)

    field, scale, units = suite.paper_metric(scenario)
    summary = {
        "source": source_args.source, "description": description, "scenario": scenario, "task_kwargs": task_kwargs,
        "split": source_args.split, "states": len(hidden), "tsne_points": len(embedding),
        "landmark": published.landmark(scenario), "metric_units": units, "heatmap_episode": heatmap_episode,
        **({"totem_probe": probe} if totem_green is not None else {}),
        "episodes": [
            {"config_index": e.config_index, "length": e.length, "return": float(e.rewards.sum()),
             "metric": float(e.infos[-1][field]) * scale, "landmark_first_seen": e.landmark_first_seen,
             **({"totem_green": bool(e.infos[0]["totem_green"])} if "totem_green" in e.infos[0] else {})}
            for e in played
        ],
        "files": [str(out / name) for name in ("states.npz", "heatmap.png", "tsne.png", "tsne.npz", "summary.json")],
    }
    files.atomic_write_json(out / "summary.json", summary)
    return summary


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    policy.policy_arguments(parser)
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--tsne-states", type=int, default=TSNE_STATES, help="states in the t-SNE")
    parser.add_argument("--max-steps", type=int, default=None, help="cut episodes after this many steps")
    parser.add_argument("--heatmap-episode", type=int, default=None, help="episode of the heatmap (default: the longest)")
    parser.add_argument("--out", type=pathlib.Path, default=None, help="default: <run>/analysis")
    args = parser.parse_args(argv)
    try:
        summary = analyse(args, args.episodes, args.out, args.tsne_states, args.max_steps, args.heatmap_episode)
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None
    seen = [e["landmark_first_seen"] for e in summary["episodes"] if e["landmark_first_seen"] is not None]
    print(f"{summary['states']} states from {len(summary['episodes'])} episodes; t-SNE of {summary['tsne_points']}; "
          f"{summary['landmark']} seen in {len(seen)} episodes")
    if "totem_probe" in summary:
        probe = summary["totem_probe"]
        print("totem's colour from the state once seen: " + (
            "too few episodes of each colour saw the totem" if probe is None else
            f"{probe['accuracy']:.1%} read out ({probe['folds']}-fold across {probe['episodes']} episodes, "
            f"{probe['states']} states; majority colour {probe['majority']:.1%})"))
    print("written: " + ", ".join(summary["files"]))


if __name__ == "__main__":
    main()
