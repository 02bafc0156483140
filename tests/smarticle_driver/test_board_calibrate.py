"""smarticle-board-calibrate against the board emulator: a scripted person measures a robot whose servos and
FSRs differ from the shipped calibration, and the files written reproduce the robot."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from smarticle_common import topics
from smarticle_driver import maestro
from smarticle_driver.board_calibration import load_fsr_calibration, load_servo_calibration
from smarticle_driver.calibrate_cli import build_parser, main, run
from smarticle_driver.emulator import MaestroEmulator
from tests.helpers.fake_board import running_emulator, wait_until

#: The robot on the bench: where each arm is straight and how many us turn it by a radian.
TRUE_SERVOS = {'arm1': (1530.0, 620.0), 'arm2': (1470.0, -590.0)}
#: Each face's reading (volts) under a force (N): a made-up sensor, different for each face.
TRUE_FSR = {face: (0.03 + 0.01 * i, 0.35 + 0.05 * i) for i, face in enumerate(topics.FSR_FACES)}
FORCES = (1.0, 3.0, 6.0)
CHANNEL = {'arm1': 0, 'arm2': 1, **dict(zip(topics.FSR_FACES, (2, 3, 4, 5), strict=True))}


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[MaestroEmulator]:
    with running_emulator(tmp_path / 'maestro') as emu:
        yield emu


def volts(face: str, newtons: float) -> float:
    rest, per_newton = TRUE_FSR[face]
    return min(rest + per_newton * newtons, maestro.ANALOG_VOLTS)


class Person:
    """Answers the prompts as a careful person would, looking at the emulated arm and applying forces."""

    def __init__(self, emulator: MaestroEmulator) -> None:
        self.emulator = emulator
        self.forces: dict[str, list[float]] = {face: list(FORCES) for face in topics.FSR_FACES}
        self.prompts: list[str] = []

    def ask(self, prompt: str) -> str:
        self.prompts.append(prompt)
        name = prompt.split()[0].rstrip(':')
        if name in TRUE_SERVOS:
            center, per_rad = TRUE_SERVOS[name]
            want = center + (per_rad * math.pi / 2 if '+90' in prompt else 0.0)
            shown = float(prompt.split(' at ')[-1].split(' us')[0])         # the pulse the prompt says was sent
            assert wait_until(lambda: abs(self.emulator.target_us(CHANNEL[name]) - shown) <= 0.13, 1.0), "not sent"
            error = want - self.emulator.target_us(CHANNEL[name])
            return '' if abs(error) <= 0.25 else f'{error:+.2f}'
        face = name
        if 'nothing touching' in prompt:
            self.emulator.set_voltage(CHANNEL[face], volts(face, 0.0))
            return ''
        if not self.forces[face]:
            self.emulator.set_voltage(CHANNEL[face], volts(face, 0.0))
            return ''
        newtons = self.forces[face].pop(0)
        self.emulator.set_voltage(CHANNEL[face], volts(face, newtons))
        return f'{newtons:g}'


def test_a_scripted_person_measures_the_robot_and_the_files_reproduce_it(
        emulator: MaestroEmulator, tmp_path: Path) -> None:
    person, said = Person(emulator), []
    args = build_parser().parse_args(['--port', str(emulator.link_path), '--out', str(tmp_path / 'cal')])
    assert run(args, person.ask, said.append) == 0, said
    servos = load_servo_calibration(tmp_path / 'cal' / 'servo_calibration.yaml')
    for name, (center, per_rad) in TRUE_SERVOS.items():
        assert servos[name].center_us == pytest.approx(center, abs=0.3)
        assert servos[name].us_per_rad == pytest.approx(per_rad, rel=0.002)
        assert servos[name].angle_to_pulse(math.radians(45)) == pytest.approx(center + per_rad * math.pi / 4, abs=0.5)
    fsrs = load_fsr_calibration(tmp_path / 'cal' / 'fsr_calibration.yaml')
    for face in topics.FSR_FACES:
        for newtons in (0.0, *FORCES):
            counts = round(volts(face, newtons) / maestro.ANALOG_VOLTS * maestro.ANALOG_FULL_SCALE)
            assert fsrs[face].newtons(counts) == pytest.approx(newtons, abs=0.05)
    assert any('wrote' in line for line in said)


def test_answers_from_a_file_and_q_stops_without_writing(emulator: MaestroEmulator, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    answers = tmp_path / 'answers.txt'
    answers.write_text('+30\n\n\nq\n', encoding='utf-8')          # arm1 nudged, accepted, +90 accepted, stop
    out = tmp_path / 'cal'
    code = main(['--port', str(emulator.link_path), '--out', str(out), '--answers', str(answers)])
    printed = capsys.readouterr().out
    assert code == 1 and not out.exists(), printed
    assert 'arm1 straight: at 1530.00 us' in printed and 'nothing written' in printed
    assert wait_until(lambda: emulator.target_us(0) == 1530.0, 1.0)     # arm1 left straight


def test_a_missing_board_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    answers = tmp_path / 'answers.txt'
    answers.write_text('\n', encoding='utf-8')
    assert main(['--port', str(tmp_path / 'none'), '--answers', str(answers)]) == 2
    assert 'cannot open' in capsys.readouterr().out
    assert main(['--port', str(tmp_path / 'none'), '--answers', str(tmp_path / 'no_answers.txt')]) == 2
    assert 'cannot read the answers' in capsys.readouterr().out
