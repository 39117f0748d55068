"""Top-down maps, line of sight, and human play (headless and in a dummy window)."""

import json
import math
import os

import imageio.v3 as iio
import numpy as np
import pytest
from conftest import find_cell, open_run, place

import mjmaze
from mjmaze import play, viz
from mjmaze.game import doom, maze


@pytest.fixture
def labyrinth5():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0})
    env.reset()
    top_down = viz.TopDown(env, 200)
    yield env, top_down
    top_down.close()
    env.task.close()


def _wall_midpoints(config):
    """(x, y, present) at the middle of every interior wall segment."""
    n, cell, half = config.size, config.cell_size, (config.size - 1) / 2
    for i in range(1, n):
        for j in range(n):
            yield (j - half) * cell, (i - 0.5 - half) * cell, bool(config.h_walls[i, j])
            yield (i - 0.5 - half) * cell, (j - half) * cell, bool(config.v_walls[j, i])


def test_the_map_shows_exactly_the_walls_of_the_configuration(labyrinth5):
    env, top_down = labyrinth5
    image = top_down.render()
    config = env.task.config
    floor = image[tuple(top_down.to_pixels(config.cell_centre(config.spawn_cell))[::-1].astype(int))].astype(int)
    for x, y, present in _wall_midpoints(config):
        col, row = top_down.to_pixels((x, y)).astype(int)
        is_floor = np.abs(image[row, col].astype(int) - floor).sum() < 30
        assert is_floor != present, (x, y, present)


def test_the_map_follows_the_maze_of_each_episode(labyrinth5):
    env, top_down = labyrinth5
    first = top_down.render()
    env.reset()  # the next configuration
    assert not np.array_equal(first, top_down.render())


def test_paths_never_cross_a_wall_and_line_of_sight_agrees(labyrinth5):
    env, top_down = labyrinth5
    rng = np.random.default_rng(0)
    poses = [env.physics.agent_pose()]
    for _ in range(300):
        if env.step(rng.integers(5)).last():
            break
        poses.append(env.physics.agent_pose())
    config = env.task.config
    for a, b in zip(poses, poses[1:]):
        assert viz.line_of_sight(config, a[:2], b[:2])
    drawn = top_down.draw(path=np.array(poses), agent_pose=poses[-1])
    assert drawn.shape == (200, 200, 3) and not np.array_equal(drawn, top_down.render())


def test_line_of_sight_is_blocked_by_a_wall_and_not_by_an_open_side(labyrinth5):
    env, _ = labyrinth5
    config = env.task.config
    walled = find_cell(config, lambda c: c[1] < config.size - 1 and not maze.is_open(config.h_walls, config.v_walls, c, (0, 1)))
    opened = find_cell(config, lambda c: c[1] < config.size - 1 and maze.is_open(config.h_walls, config.v_walls, c, (0, 1)))
    for cell, expected in ((walled, False), (opened, True)):
        start = config.cell_centre(cell)
        end = config.cell_centre((cell[0], cell[1] + 1))
        assert viz.line_of_sight(config, start, end) is expected


def test_in_view_needs_the_field_of_view_and_a_clear_line(labyrinth5):
    env, _ = labyrinth5
    config = env.task.config
    cell = find_cell(config, lambda c: c[1] < config.size - 2 and open_run(config, c, 2))
    x, y = config.cell_centre(cell)
    target = config.cell_centre((cell[0], cell[1] + 2))
    assert viz.in_view(env.task, (x, y, 0.0), target)  # straight ahead
    assert viz.in_view(env.task, (x, y, math.radians(45)), target)  # inside the 106 deg field
    assert not viz.in_view(env.task, (x, y, math.pi), target)  # behind
    assert not viz.in_view(env.task, (x, y, math.pi / 2), target)  # to the side
    assert math.degrees(viz.horizontal_fov(env.task)) == pytest.approx(106.3, abs=0.1)  # Doom's 2 atan(160 / 120)


def test_map_cli_writes_a_picture_with_a_path(tmp_path, capsys):
    out = tmp_path / "map.png"
    viz.main(["--scenario", "two_colour", "--complexity", "5", "--config", "3", "--random-steps", "50",
              "--map-size", "128", "--out", str(out)])
    image = iio.imread(out)
    # The 128-pixel map, then its key below: spawn, path, agent, the totem and items in their colours.
    assert image.shape[1] == 128 and image.shape[0] > 128 and image[:128].std() > 10
    assert "configuration 3" in capsys.readouterr().out


def test_the_map_key_names_what_is_drawn_in_its_colours(labyrinth5):
    _, top_down = labyrinth5
    entries = dict(top_down.legend())
    assert list(entries)[:3] == ["spawn", "path", "agent"] and entries["spawn"] == viz.SPAWN_COLOUR
    assert "exit" in entries  # the scenario's object, in its map colour
    keyed = viz.with_legend(top_down.draw(), top_down.legend())
    assert keyed.shape[1] == 200 and keyed.shape[0] > 200  # wrapped to the map's width


def test_compose_puts_text_above_the_scaled_view_and_the_map():
    ego = np.full((64, 112, 3), 200, np.uint8)
    top = np.zeros((256, 256, 3), np.uint8)
    frame = viz.compose(ego, top, ["hello"], scale=4)
    assert frame.shape[0] % 16 == 0 and frame.shape[1] == 448 + 256
    assert (frame[:, :448] == 200).all(axis=2).sum() == 256 * 448  # the view, scaled 4x
    assert frame[:20].std() > 0  # the text


# -- human play --------------------------------------------------------------------


def test_key_tokens_map_to_the_action_set():
    assert play.parse_token("w") == (1, 0) and play.parse_token("wa") == (1, 1) and play.parse_token("D") == (0, -1)
    assert [play.action_for(*play.parse_token(t)) for t in ("a", "d", "w", "wa", "wd")] == [0, 1, 2, 3, 4]
    assert play.action_for(-1, 0) is None and play.action_for(-1, 0, "extended") == 5
    with pytest.raises(ValueError, match="use letters"):
        play.parse_token("x")


def test_headless_replay_moves_the_agent_and_writes_the_session(tmp_path):
    out = tmp_path / "play"
    play.main(["--scenario", "k_item", "--num-items", "4", "--size", "5", "--keys", "a a a d d d", "--out", str(out)])
    session = json.loads((out / "session.json").read_text())
    assert session["actions"] == [0, 0, 0, 1, 1, 1] and session["task_kwargs"]["num_items"] == 4
    screen = iio.imread(out / "screen.png")
    assert screen.shape[1] == 448 + 256 and screen.std() > 10

    replayed = play.PlaySession("labyrinth", {"size": 5})
    try:
        start = replayed.poses[-1]
        play.replay(replayed, ["a", "a"])
        assert math.degrees(math.remainder(replayed.poses[-1][2] - start[2], math.tau)) == pytest.approx(7.0 + 12.3, abs=0.2)  # a turn starts slow
        config = replayed.env.task.config
        cell = find_cell(config, lambda c: c[1] < config.size - 1 and open_run(config, c, 1))
        place(replayed.env, *config.cell_centre(cell), 0.0)
        before = replayed.env.physics.agent_pose()
        play.replay(replayed, ["w"])
        assert replayed.poses[-1][0] - before[0] == pytest.approx(7.1 * doom.MAP_UNIT, abs=0.005)  # one step from rest
    finally:
        replayed.close()


def test_a_move_the_action_set_lacks_is_one_clear_error_and_the_session_is_kept(tmp_path):
    out = tmp_path / "play"
    with pytest.raises(SystemExit, match="no move of the 'default' action set"):
        play.main(["--keys", "w s", "--out", str(out)])
    assert json.loads((out / "session.json").read_text())["actions"] == [2]


def test_the_window_steps_while_a_key_is_held(monkeypatch):
    pygame = pytest.importorskip("pygame")
    monkeypatch.setitem(os.environ, "SDL_VIDEODRIVER", "dummy")
    session = play.PlaySession("labyrinth", {"size": 5})
    try:
        pygame.display.init()
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_UP))
        play.run_window(session, max_frames=4)
        assert session.actions == [2, 2, 2, 2]
        pygame.display.init()
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_r))
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE))
        play.run_window(session)  # R ends the episode, Esc quits at once
        assert len(session.episodes) == 1 and session.episodes[0]["steps"] == 4
    finally:
        session.close()


@pytest.fixture
def x_display():
    """A virtual X display (Xvfb), as a person at a desktop has one."""
    import shutil
    import subprocess
    import time

    if not (shutil.which("Xvfb") and shutil.which("xdotool")):
        pytest.skip("needs Xvfb and xdotool (make test installs them: apt-get install xvfb xdotool)")
    number = 90 + os.getpid() % 100
    server = subprocess.Popen(["Xvfb", f":{number}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 20
    while not os.path.exists(f"/tmp/.X11-unix/X{number}"):
        assert server.poll() is None and time.monotonic() < deadline, "Xvfb did not start"
        time.sleep(0.05)
    yield f":{number}"
    server.terminate()
    server.wait(timeout=10)


@pytest.mark.display
@pytest.mark.slow
def test_the_play_window_under_a_real_x_display_takes_keys(tmp_path, x_display):
    import subprocess
    import sys

    pytest.importorskip("pygame")
    env = {key: value for key, value in os.environ.items() if key not in ("MUJOCO_GL", "SDL_VIDEODRIVER", "PYOPENGL_PLATFORM")}
    env["DISPLAY"] = x_display
    out = tmp_path / "play"
    game = subprocess.Popen([sys.executable, "-m", "mjmaze.play", "--scenario", "labyrinth", "--size", "5",
                             "--out", str(out)], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        # By process id: SDL sets the title as a UTF-8 WM_NAME, which `search --name` misses.
        found = subprocess.run(["xdotool", "search", "--sync", "--pid", str(game.pid)], env=env, capture_output=True,
                               text=True, timeout=90)
        window = found.stdout.split()[0]
        xdo = lambda *args: subprocess.run(["xdotool", *args], env=env, check=True, timeout=20)  # noqa: E731
        xdo("windowfocus", "--sync", window)
        xdo("keydown", "w")
        xdo("sleep", "1")
        xdo("keyup", "w")
        xdo("key", "Escape")
        output, _ = game.communicate(timeout=60)
    finally:
        if game.poll() is None:
            game.kill()
    assert game.returncode == 0 and "X Error" not in output, output
    session = json.loads((out / "session.json").read_text())
    assert session["actions"] and set(session["actions"]) == {2}  # forward while W was held
    assert iio.imread(out / "screen.png").std() > 0
