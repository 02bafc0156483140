"""The README's main command: its two scenes, their batch twins, the printout, the figures and the animation."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from smarticle_bringup.demo_scenes import (FEEDBACK, GLIDERS, MIN_PERIODS, TRAVEL_MIN_W_PER_100, analyse, run_batch,
                                           travelling)

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))   # the repository root: tests.* helpers
from tests.helpers.glider_scenes import pair_scene as synthetic_pair  # noqa: E402


def stack_windows() -> dict[str, object]:
    """The shared windows the demo's feedback nodes read (config/stack.yaml)."""
    import yaml

    data = yaml.safe_load((ROOT / 'smarticle_bringup' / 'config' / 'stack.yaml').read_text(encoding='utf-8'))
    return dict(data['/**']['ros__parameters'])


@pytest.mark.integration
@pytest.mark.slow
def test_demo_runs_both_parts_and_equals_the_batch_path(tmp_path: Path) -> None:
    """A short default demo: both parts over DDS, the glider table, halts > 0, figures, the animation, bags;
    and each part's poses (and halts) are the batch core's for the same scene and seed, so the seed table of
    tests/benchmarks/demo_seeds.py is what the demo runs."""
    out = tmp_path / 'demo'
    # a relative output folder, as ./demo.sh uses (out/demo): the launch files must not resolve it themselves
    proc = subprocess.run([sys.executable, '-m', 'smarticle_bringup.demo', '--periods', '3', '--feedback-periods',
                           '2', '--frame-step', '0.4', '--out', 'demo'], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    text = proc.stdout
    assert text.startswith('[demo] chose: ') and 'docs/demo.md' in text.splitlines()[0]
    assert text.count('lifetime [periods]') + text.count('\n  none') == 2          # a glider table per part
    assert '[demo] not reproduced: ' in text and 'docs/sim_calibration.md' in text
    halts_line = next(line for line in text.splitlines() if 'feedback halts per robot' in line)
    counts = [int(c.split(': ')[1]) for c in halts_line.split('robot: ')[1].split(' (')[0].split(', ')]
    assert len(counts) == 2 and sum(counts) > 0, halts_line
    assert 'composed in one process' in text
    assert len(list((out / 'gliders' / 'logs').glob('smarticle-compose-*.log'))) == 1
    feedback_host = next((out / 'feedback' / 'logs').glob('smarticle-compose-*.log')).read_text()
    assert feedback_host.count('windows') == 2                       # each feedback node started
    graph = (out / 'feedback' / 'nodes.txt').read_text().split()     # the ROS graph during the run
    assert len(graph) == len(set(graph)) and {'/sim_bridge', '/glider_monitor'} <= set(graph), graph
    for k in range(2):
        assert f'/smarticle_{k}/gait' in graph and f'/smarticle_{k}/feedback' in graph, graph
    for scene, periods in ((GLIDERS, 3.0), (FEEDBACK, 2.0)):
        data = np.load(out / scene.key / 'poses.npz')
        assert data['time'][-1] == pytest.approx(periods * 1.6, abs=0.05)
        batch = run_batch(scene, 1, periods, windows=stack_windows())
        assert data['poses'].shape == batch.poses.shape
        np.testing.assert_allclose(data['poses'], batch.poses, rtol=0, atol=1e-9)
        arms = data['arm_angles']                         # the joint states the animation draws the arms from
        seen = np.isfinite(arms).all(axis=(1, 2))
        assert seen.mean() > 0.9
        np.testing.assert_allclose(arms[seen], batch.arms[seen], rtol=0, atol=1e-9)
        assert (out / scene.key / 'trajectories.png').stat().st_size > 10_000
        from smarticle_bags.arrays import read_poses
        from smarticle_bags.reader import BagReader

        recorded = read_poses(BagReader(out / scene.key / 'bag'))   # the bag holds the poses the demo analysed
        assert len(recorded.stamp) >= 0.9 * len(data['time'])
        # recorded in sim time: the bag lasts the simulated run (start_at 0.5 s + the periods), not its wall time
        bag_info = BagReader(out / scene.key / 'bag').info
        assert bag_info.duration * 1e-9 == pytest.approx(0.5 + periods * 1.6, abs=0.1), bag_info.duration
    assert sum(counts) == len(run_batch(FEEDBACK, 1, 2.0, windows=stack_windows()).halts)
    assert (out / 'feedback' / 'halts.png').stat().st_size > 10_000
    from PIL import Image

    with Image.open(out / 'demo.gif') as gif:
        assert gif.n_frames >= (3 + 2) * 1.6 / 0.4
        assert gif.size[0] > 200


@pytest.mark.integration
@pytest.mark.slow
def test_demo_feedback_part_open_loop_as_separate_processes(tmp_path: Path) -> None:
    out = tmp_path / 'demo'
    proc = subprocess.run([sys.executable, '-m', 'smarticle_bringup.demo', '--only', 'feedback', '--no-feedback',
                           '--feedback-periods', '2', '--separate', '--no-animation', '--out', str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert 'feedback nodes' not in proc.stdout and 'feedback halts per robot' not in proc.stdout
    assert 'the controller off (--no-feedback)' in proc.stdout
    assert 'as separate processes' in proc.stdout and not (out / 'demo.gif').exists()
    logs = out / 'feedback' / 'logs'
    assert not list(logs.glob('feedback-*.log')) and len(list(logs.glob('gait-*.log'))) == 2
    assert np.load(out / 'feedback' / 'poses.npz')['poses'].shape[1:] == (2, 3)
    assert not (out / 'gliders').exists()


@pytest.mark.slow
def test_the_default_seed_glides_and_travels() -> None:
    """The demo's default seed, its gliders scene in the batch core: a bound pair that travels, a glider."""
    run = run_batch(GLIDERS, 1)
    gliders = analyse(GLIDERS, run.times, run.poses).gliders
    assert not run.trouble and any(travelling(g) and g.label == 'C1 glider' for g in gliders), gliders


def test_the_gliders_scene_starts_where_p5_starts_its_pairs() -> None:
    """Seed s of the demo's gliders scene is seed s of P5's pair start (its spec's jitter) at 0.1 period."""
    import yaml
    from smarticle_experiments.trials import pair_start

    spec = yaml.safe_load((ROOT / 'smarticle_experiments' / 'config' / 'experiments' / 'p5.yaml').read_text())
    for seed in range(10):
        start = GLIDERS.start_for(seed)
        assert (start.r_bl, start.theta_deg, start.phi_deg) == pytest.approx(pair_start(spec['params'], seed))
    assert GLIDERS.start.phases == (0.0, spec['params']['phase2'])


@pytest.mark.parametrize('scene', [GLIDERS, FEEDBACK], ids=lambda s: s.key)
def test_the_sim_bridge_builds_the_scene_the_batch_path_runs(scene: object) -> None:
    """The demo's bridge parameters make the sim bridge place the robots exactly as the batch twin does."""
    from smarticle_sim.bridge import BridgeSettings

    for seed in (0, 1, 7):
        values = scene.bridge_params(seed)          # type: ignore[attr-defined]
        values.pop('phase_jitter')
        built = BridgeSettings.defaults(scene='pair', robots=2, seed=seed, **values).scene()
        assert built.robots == scene.scene(seed).robots   # type: ignore[attr-defined]
        assert [p['phase'] for p in scene.robot_params(seed)] == list(scene.start_for(seed).phases)  # type: ignore[attr-defined]


def test_demo_rule_is_the_documented_one() -> None:
    """The demo's words are the glider analysis's: bound >= 30 periods under 1.6 BL, travelling >= 1 W per 100."""
    from smarticle_tracking.gliders import GliderConfig

    assert (MIN_PERIODS, TRAVEL_MIN_W_PER_100) == (30, 1.0)
    config = GLIDERS.glider_config()
    assert (config.min_periods, config.travel_min_w_per_100) == (GliderConfig().min_periods,
                                                                 GliderConfig().travel_min_w_per_100)
    assert config.r_bind == pytest.approx(1.6 * GLIDERS.spec.body_length)
    assert FEEDBACK.glider_config().width == FEEDBACK.spec.body_length


def test_glider_lines_show_class_lifetime_and_travel() -> None:
    from smarticle_bringup.demo import glider_lines
    from smarticle_tracking.gliders import GliderConfig, analyse_gliders

    times, poses = synthetic_pair([True] * 35 + [False] * 5, phi=math.pi, velocity=(0.002, 0.0))
    config = GliderConfig(min_periods=MIN_PERIODS)
    gliders = analyse_gliders(times, poses, config).gliders
    text = glider_lines(gliders, config.width)
    header, row = text.splitlines()
    assert 'what' in header and 'lifetime [periods]' in header and 'travel [W]' in header
    assert 'travels (>= 1 W per 100 periods)' in header
    cells = row.split()
    assert cells[:6] == ['0-1', 'C1', 'glider', '180', '0', '35'] and cells[-1] == 'yes'
    assert float(cells[-3]) == pytest.approx(gliders[0].distance / config.width, abs=0.01)
    assert float(cells[-2]) == pytest.approx(gliders[0].travel_w_per_100, abs=0.05)
    still = analyse_gliders(*synthetic_pair([True] * 35 + [False] * 5, phi=math.pi), config).gliders
    cells = glider_lines(still, config.width).splitlines()[1].split()
    assert cells[1:4] == ['C1', 'bound', 'pair'] and cells[-1] == 'no'     # a still pair is no glider
    assert glider_lines((), 0.054) == '  none'


def test_animation_draws_three_links_per_robot_and_the_halts(tmp_path: Path) -> None:
    from PIL import Image
    from smarticle_bringup.demo_figures import AnimatedPart, GliderSpan, robot_outlines, write_animation

    outlines = robot_outlines(GLIDERS.spec, (0.0, 0.0, math.pi / 2), (math.pi / 2, math.pi / 2))
    assert len(outlines) == 3 and all(o.shape == (4, 2) for o in outlines)
    body_width = np.linalg.norm(outlines[0][0] - outlines[0][1])
    assert body_width == pytest.approx(GLIDERS.spec.body_width)
    times, poses = synthetic_pair([True] * 4, n_robots=2)
    arms = np.zeros((len(times), 2, 2))
    halts = [(1.0, 0, 'arm1_front')]
    span = GliderSpan(0, 1, 'C1', 0.0, 6.4, 0.1, ('bound', 'C1 bound pair', 'C1 glider', 'C1 glider'))
    assert [span.label_at(t) for t in (0.0, 1.5, 1.6, 3.3, 5.0, 6.4)] == [None, None, 'bound', 'C1 bound pair',
                                                                         'C1 glider', None]
    parts = [AnimatedPart('1 gliders', GLIDERS.spec, times, poses, arms, [span]),
             AnimatedPart('2 feedback', GLIDERS.spec, times, poses, arms, (), halts)]
    path = write_animation(parts, tmp_path / 'a.gif', step=0.4)
    with Image.open(path) as gif:
        frames = gif.n_frames
        gif.seek(0)
        first = np.asarray(gif.convert('RGB'))
        gif.seek(4)                 # part 1, t = 1.6 s: bound one period, not yet a bound pair: no class colour
        one_period = np.asarray(gif.convert('RGB'))
        gif.seek(8)                 # part 1, t = 3.2 s: the run so far is a C1 bound pair
        labelled = np.asarray(gif.convert('RGB'))
        gif.seek(frames // 2 + 1)   # part 2, t = 0.4 s: before the halt
        before = np.asarray(gif.convert('RGB'))
        gif.seek(frames // 2 + 3)   # part 2, t = 1.2 s: robot 0 holds after its halt at 1.0 s
        halted = np.asarray(gif.convert('RGB'))
        gif.seek(frames // 2 + 5)   # part 2, t = 2.0 s: its next period began, it moves again
        resumed = np.asarray(gif.convert('RGB'))
    assert frames == 2 * 16
    def blues(image: np.ndarray) -> int:    # the C1 class colour
        return int(np.all(np.abs(image.astype(int) - (0x2a, 0x8c, 0xff)) < 30, axis=-1).sum())

    red = np.all(np.abs(halted.astype(int) - (0xd6, 0x27, 0x28)) < 30, axis=-1)    # a halted robot's outline
    assert blues(first) == 0 and blues(one_period) == 0 and blues(labelled) > 100 and red.sum() > 20

    def reds(image: np.ndarray) -> int:
        return int(np.all(np.abs(image.astype(int) - (0xd6, 0x27, 0x28)) < 30, axis=-1).sum())

    assert reds(before) == 0 and reds(resumed) == 0


def test_halts_figure(tmp_path: Path) -> None:
    from smarticle_bringup.demo_figures import plot_halts

    times, poses = synthetic_pair([True, False, True], n_robots=2)
    path = plot_halts(times, poses, [(0.5, 0, 'arm1_front'), (2.0, 1, 'arm2_back')], 0.054, tmp_path / 'h.png', 't')
    assert path.stat().st_size > 10_000


def test_clock_noise_gives_each_robot_the_batch_paths_clock_offset(tmp_path: Path) -> None:
    """--clock-noise writes each robot's clock_rate_offset (gait and feedback alike): the batch path's draw."""
    import yaml
    from smarticle_bringup.demo import build_parser, plan_parts, write_params
    from smarticle_sim.noise import clock_rates
    from smarticle_sim.settings import NoiseConfig

    path = tmp_path / 'params.yaml'
    args = build_parser().parse_args(['--seed', '4', '--clock-noise'])
    expected = clock_rates(NoiseConfig.paper(), 2, 4)
    assert np.any(expected != 0.0)
    for part in plan_parts(args):
        write_params(part, args, path)
        data = yaml.safe_load(path.read_text(encoding='utf-8'))
        assert data['/sim_bridge']['ros__parameters']['preset'] == part.spec.name
        for k in range(2):
            gait, feedback = (data[f'/smarticle_{k}/{node}']['ros__parameters'] for node in ('gait', 'feedback'))
            assert gait['clock_rate_offset'] == feedback['clock_rate_offset'] == expected[k]
            assert gait['phase'] == feedback['phase']
            assert gait['servo_speed'] == part.spec.servo_speed
    args = build_parser().parse_args(['--seed', '4'])
    write_params(plan_parts(args)[0], args, path)
    data = yaml.safe_load(path.read_text(encoding='utf-8'))
    assert all('clock_rate_offset' not in data[f'/smarticle_{k}/gait']['ros__parameters'] for k in range(2))


def test_dense_start() -> None:
    from smarticle_bringup.demo import build_parser, plan_parts

    parts = plan_parts(build_parser().parse_args(['--scene', 'dense', '--robots', '5', '--only', 'gliders']))
    assert [(p.scene_kind, p.robots, p.feedback) for p in parts] == [('dense', 5, False)]
    assert len({p['phase'] for p in parts[0].own}) == 5          # the dense start's phase jitter


#: Bad demo options -> what the one line must name (the option and, where a node's range decides, its parameter).
BAD_OPTIONS = {
    '--alpha-max nan': ('--alpha-max', "'alpha_max_deg': NaN"),
    '--alpha-max 200': ('--alpha-max', 'above the maximum 120'),
    '--alpha-max 2': ('--alpha-max', 'below the minimum 5'),
    '--periods nan': ('--periods', 'nan'),
    '--periods 0': ('--periods', '> 0'),
    '--periods 1e9': ('--periods', "'duration'"),
    '--feedback-periods -1': ('--feedback-periods', '> 0'),
    '--seed -1': ('--seed', 'non-negative'),
    '--seed 1.5': ('--seed', "'1.5'"),
    '--robots 0': ('--robots', 'below the minimum 1'),
    '--phase-offset 1.5': ('--phase-offset', "'pair_phase_1'"),
    '--phase-jitter nan': ('--phase-jitter', 'NaN'),
    '--frame-step inf': ('--frame-step', '> 0'),
    '--view --view-port 70000': ('--view-port', 'above the maximum 65535'),
    '--alpha-max x': ('--alpha-max', "'x'"),
}


@pytest.mark.parametrize('options', sorted(BAD_OPTIONS))
def test_a_bad_option_is_one_line_and_exit_2_before_anything_starts(options: str, tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """Each option checked as the node parameter it becomes checks it: one line naming it, exit 2, nothing run."""
    from smarticle_bringup.demo import main

    out = tmp_path / 'demo'
    try:
        code = main([*options.split(), '--out', str(out)], prog='demo.sh')
    except SystemExit as exc:   # argparse's own refusals (not a number, not a seed)
        code = int(exc.code or 0)
    err = capsys.readouterr().err
    option, cause = BAD_OPTIONS[options]
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith('demo.sh: error: ') and option in err and cause in err, err
    assert not out.exists()


def test_a_bad_option_from_the_shell_is_one_line_without_a_traceback(tmp_path: Path) -> None:
    proc = subprocess.run([sys.executable, '-m', 'smarticle_bringup.demo', '--alpha-max', 'nan', '--out',
                           str(tmp_path / 'demo')], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == '', proc.stdout
    assert proc.stderr.splitlines() == ["demo.sh: error: --alpha-max: the gait and sim bridge parameter "
                                        "'alpha_max_deg': NaN is not allowed"], proc.stderr
