"""Episode videos: the agent's view beside the top-down map with its path growing.

    python -m mjmaze.train.record runs/labyrinth_5_s0 --episodes 4 --out episode.mp4
    python -m mjmaze.train.record random --scenario k_item --num-items 4 --episodes 2 --out k_item.mp4

Each frame shows the ego view (scaled 4x), the map as it is at that step (items
vanish when picked up) with the path so far, and above them the run, the
configuration, the step, the return and the scenario's metric. MP4 through
imageio's ffmpeg (the binary ships with the imageio-ffmpeg package); a GIF when
``--out`` ends in ``.gif`` or ffmpeg is missing. Beside the video,
``<out>.json`` holds each episode's configuration, length, return, metric and
path. Both are written to temporary files and renamed into place.
"""

from __future__ import annotations

import argparse
import pathlib

import imageio.v2 as imageio
import numpy as np
from tqdm import tqdm

import mjmaze
from mjmaze import files, viz
from mjmaze.backends import suite
from mjmaze.game import core

from . import checkpoint, policy
from .settings import using_torch_threads

FPS = core.STEPS_PER_SECOND  # real time: one frame per agent step
MAP_SIZE = 256


def _ffmpeg_available() -> bool:
    try:
        import imageio_ffmpeg

        imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return False
    return True


def video_path(out: pathlib.Path) -> pathlib.Path:
    """Where the video goes: ``out``, or ``out`` as a GIF where MP4 cannot be written."""
    if out.suffix.lower() != ".gif" and not _ffmpeg_available():
        print("imageio-ffmpeg is not installed: writing a GIF instead (pip install imageio-ffmpeg for MP4)")
        return out.with_suffix(".gif")
    return out


#: A GIF stores every frame whole (a K-item episode's 1,000 frames made 20 MB): it
#: keeps every GIF_STRIDE-th frame at half size, shown as long (MP4 keeps them all).
GIF_STRIDE = 2


def _writer(path: pathlib.Path, fps: float):
    if path.suffix.lower() == ".gif":
        return imageio.get_writer(path, format="GIF", duration=1000 * GIF_STRIDE / fps, loop=0)
    return imageio.get_writer(path, format="FFMPEG", fps=fps, codec="libx264", macro_block_size=viz.VIDEO_BLOCK)


def episode_frames(episode: policy.Episode, top_down: viz.TopDown, scenario: str, header: str,
                   title: str):
    """The video frames of one played episode (kept frames and maps), one per step and one at the end."""
    episode_return = 0.0
    legend = top_down.legend()
    for t in range(len(episode.poses)):
        if t > 0:
            episode_return += episode.rewards[t - 1]
        status = f"step {t:3d}  return {episode_return:+.3f}"
        if t > 0:
            status += "  " + policy.metric_of(scenario, episode.infos[t - 1])
        top = top_down.draw(episode.maps[t], path=episode.poses[: t + 1], agent_pose=episode.poses[t])
        yield viz.compose(episode.frames[t], viz.with_legend(top, legend), [header, f"{title}  {status}"])


def record(source_args: argparse.Namespace, episodes: int, out: pathlib.Path, fps: float = FPS,
           max_steps: int | None = None) -> dict:
    """Plays ``episodes`` episodes and writes the video and its JSON summary; returns the summary."""
    scenario, task_kwargs, agent_policy, description = policy.policy_from_arguments(source_args)
    env = mjmaze.load(scenario, task_kwargs={**task_kwargs, "split": source_args.split, "random": source_args.seed})
    top_down = viz.TopDown(env, MAP_SIZE)
    path = video_path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    header = f"{description} | {scenario} {policy.describe(task_kwargs)} | {source_args.split}"
    field, scale, units = suite.paper_metric(scenario)
    summary = {"video": str(path), "source": source_args.source, "scenario": scenario, "task_kwargs": task_kwargs,
               "split": source_args.split, "fps": fps, "frames": 0, "metric_units": units, "episodes": []}
    try:
        writer = _writer(tmp, fps)
        try:
            for k in tqdm(range(episodes), desc="episodes", unit="ep", leave=False, disable=None, dynamic_ncols=True):
                # One episode at a time: its maps are the memory-hungry part.
                with using_torch_threads(policy.threads_of(source_args)):
                    (episode,) = policy.play_episodes(env, agent_policy, 1, keep_frames=True, top_down=top_down,
                                                      max_steps=max_steps)
                title = f"episode {k + 1}/{episodes}  config {episode.config_index}"
                gif = path.suffix.lower() == ".gif"
                for k, frame in enumerate(episode_frames(episode, top_down, scenario, header, title)):
                    if gif and k % GIF_STRIDE:
                        continue
                    writer.append_data(frame[::2, ::2] if gif else frame)
                    summary["frames"] += 1
                final = episode.infos[-1] if episode.infos else {field: 0}
                summary["episodes"].append({
                    "config_index": episode.config_index, "length": episode.length,
                    "return": float(episode.rewards.sum()), "metric": float(final[field]) * scale,
                    "path": np.round(episode.poses, 4).tolist(),
                })
        finally:
            writer.close()
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        top_down.close()
        env.task.close()
    files.atomic_write_json(path.with_suffix(".json"), summary)
    return summary


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    policy.policy_arguments(parser)
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("episode.mp4"))
    parser.add_argument("--fps", type=float, default=FPS, help="frames per second (default: real time)")
    parser.add_argument("--max-steps", type=int, default=None, help="cut episodes after this many steps")
    args = parser.parse_args(argv)
    try:
        summary = record(args, args.episodes, args.out, args.fps, args.max_steps)
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None
    units = summary["metric_units"]
    for k, e in enumerate(summary["episodes"]):
        print(f"episode {k + 1}: config {e['config_index']}, {e['length']} steps, return {e['return']:+.3f}, "
              f"{units} {e['metric']:.3g}")
    print(f"written: {summary['video']} ({summary['frames']} frames), {pathlib.Path(summary['video']).with_suffix('.json')}")


if __name__ == "__main__":
    main()
