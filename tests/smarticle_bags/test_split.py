"""Split recordings: after a SIGKILL every closed file reads with rosbags as it is; reindex fixes the last."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader as RosbagsReader

from smarticle_bags import arrays, cli, mcapfile
from smarticle_bags.errors import CorruptBagError
from smarticle_bags.metadata import read_metadata
from smarticle_bags.reader import BagReader
from smarticle_bags.reindex import reindex

from tests.helpers.ros import ROOT
from tests.helpers.bags import POSES, T0

STEP = 10_000_000  # 100 Hz
COUNT = 350  # 3.5 s of log time
FLUSH_EVERY = 25

CHILD = f'''
import os, signal, sys
from smarticle_bags.writer import BagWriter, WriterOptions
from tests.helpers.bags import pose_array
writer = BagWriter(sys.argv[1], WriterOptions(chunk_size=2000, max_bag_duration=int(sys.argv[2]),
                                              max_bag_size=int(sys.argv[3])))
writer.add_topic('{POSES}', 'geometry_msgs/msg/PoseArray')
for i in range({COUNT}):
    writer.write('{POSES}', pose_array(i), {T0} + i * {STEP})
    if i % {FLUSH_EVERY} == {FLUSH_EVERY - 1}:
        writer.flush()   # what the recorder's flush timer does
os.kill(os.getpid(), signal.SIGKILL)
'''


def record_and_kill(out: Path, max_duration: int = 0, max_size: int = 0) -> None:
    """Write a split bag in a child process that is SIGKILLed before it can close the last file."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get('PYTHONPATH', '')]))
    done = subprocess.run([sys.executable, '-c', CHILD, str(out), str(max_duration), str(max_size)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == -signal.SIGKILL, done.stderr


def rosbags_count(folder: Path) -> int:
    """Number of messages rosbags reads from a bag folder."""
    with RosbagsReader(folder) as reader:
        return sum(1 for _ in reader.messages())


@pytest.mark.parametrize('limit', ['duration', 'size'])
def test_split_recording_after_sigkill(tmp_path: Path, limit: str,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'run'
    if limit == 'duration':
        record_and_kill(out, max_duration=1_000_000_000)
    else:
        record_and_kill(out, max_size=6000)
    files = [out / f.path for f in read_metadata(out).files]  # metadata.yaml lists every file
    assert len(files) >= 3 and [f.name for f in files[:2]] == ['run_0.mcap', 'run_1.mcap']
    assert sorted(out.glob('*.mcap')) == sorted(files)
    flushed = COUNT - COUNT % FLUSH_EVERY  # what the last flush put on disk
    # every file but the last is complete, with its summary, and reads with rosbags as it is
    closed = 0
    for index, path in enumerate(files[:-1]):
        scan = mcapfile.scan(path, verify=True)
        assert scan.complete and not scan.problems, scan.problems
        single = tmp_path / f'single_{index}'
        single.mkdir()
        shutil.copy2(path, single / path.name)
        assert not reindex(single).repaired  # only metadata.yaml is written; the file is used as it is
        assert (single / path.name).read_bytes() == path.read_bytes()
        closed += rosbags_count(single)
    if limit == 'duration':
        assert closed == 300
    last = mcapfile.scan(files[-1])
    assert not last.complete and last.problems
    # read as one bag: info, arrays (analysis input), messages in time order across the files
    reader = BagReader(out)
    assert reader.info.message_count == flushed == sum(1 for _ in reader.messages())
    poses = arrays.read_poses(reader)
    np.testing.assert_array_equal(np.round(poses.stamp), np.floor(np.arange(flushed)))
    with pytest.raises(SystemExit) as info:
        cli.main(['info', str(out)])
    text = capsys.readouterr().out
    assert info.value.code == 0 and all(f.name in text for f in files) and f'Messages:          {flushed}' in text
    # reindex beside, then in place: the last file becomes complete and rosbags reads the whole bag
    beside = reindex(out)
    assert beside.output == tmp_path / 'run.repaired' and rosbags_count(beside.output) == flushed
    report = reindex(out, replace=True)
    assert report.repaired == [f'{files[-1].name} (original kept as {files[-1].name}.damaged)']
    assert rosbags_count(out) == flushed
    assert BagReader(out, strict=True).info.message_count == flushed


@pytest.mark.parametrize('damage', ['header only', 'zeroed'])
def test_split_bag_with_an_empty_or_zeroed_last_file(tmp_path: Path, damage: str) -> None:
    out = tmp_path / 'run'
    record_and_kill(out, max_duration=1_000_000_000)
    last = out / read_metadata(out).files[-1].path
    data = last.read_bytes()
    last.write_bytes(data[:40] if damage == 'header only' else bytes(len(data)))
    reader = BagReader(out)  # the other files still read; the last one is reported
    assert reader.problems and sum(1 for _ in reader.messages()) == 300
    with pytest.raises(CorruptBagError, match=last.name):
        BagReader(out, strict=True)
    report = reindex(out)
    assert report.output is not None and rosbags_count(report.output) == 300
