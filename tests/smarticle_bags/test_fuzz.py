"""Seeded fuzz test: 1,000 random and targeted mutations of a bag; never a traceback, only exit 0 or 2.

Each mutated bag goes through ``smarticle-bag check``, the columnar analysis input (``arrays.read_*``)
and ``smarticle-bag reindex`` (the CLI's main
function, in this process); whatever reindex salvages must read strictly, decode (with the independent
rosbags deserialiser, for speed), and be a subset of the original messages, byte for byte. The figures
are printed (``pytest -s``) for docs/bags.md.
"""

from __future__ import annotations

import contextlib
import io
import logging
import random
import shutil
import struct
from pathlib import Path

from smarticle_bags import arrays, cli
from smarticle_bags.errors import BagError
from smarticle_bags.reader import BagReader

from tests.helpers.bags import STORE, make_bag

SEED = 15
MUTATIONS = 1000


def _records(data: bytes) -> list[tuple[int, int]]:
    """Return (offset, total length) of the top-level records of an intact .mcap."""
    out, pos = [], 8
    while pos + 9 <= len(data) - 8:
        _, length = struct.unpack_from('<BQ', data, pos)
        out.append((pos, 9 + length))
        pos += 9 + length
    return out


def mutate(data: bytes, rng: random.Random, index: int) -> tuple[str, bytes]:
    """Return (description, mutated copy of ``data``): flips, targeted flips, cuts, zeroed runs, edits."""
    out = bytearray(data)
    kind = index % 10
    if kind < 4:  # 1-3 random bytes anywhere
        spots = [rng.randrange(len(out)) for _ in range(rng.randint(1, 3))]
        for at in spots:
            out[at] ^= rng.randint(1, 255)
        return f'flip bytes {spots}', bytes(out)
    if kind < 7:  # one byte of a chosen record: its prefix or its body
        offset, length = rng.choice(_records(data))
        at = offset + (rng.randrange(9) if rng.random() < 0.3 else rng.randrange(length))
        out[at] ^= 1 << rng.randrange(8)
        return f'flip bit in record at {offset}, byte {at}', bytes(out)
    if kind == 7:
        cut = rng.randrange(len(out))
        return f'truncate at {cut}', bytes(out[:cut])
    if kind == 8:
        start = rng.randrange(len(out))
        end = min(len(out), start + rng.randint(1, 600))
        out[start:end] = bytes(end - start)
        return f'zero bytes {start}..{end}', bytes(out)
    at = rng.randrange(len(out))
    if rng.random() < 0.5:
        del out[at:at + rng.randint(1, 16)]
        return f'delete bytes at {at}', bytes(out)
    out[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 16)))
    return f'insert bytes at {at}', bytes(out)


def _main(args: list[str]) -> int:
    """Run the CLI in this process with its output swallowed; return the exit code."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            cli.main(args)
        except SystemExit as done:
            return int(done.code or 0)
    return 0


def test_fuzz_no_traceback_and_salvage_is_subset(tmp_path: Path) -> None:
    original = tmp_path / 'orig'
    written = make_bag(original, 30)
    everything = {(topic, t, data) for topic, items in written.items() for t, data in items}
    pose_stamps = set(arrays.read_poses(BagReader(original)).stamp.tolist())
    mcap_name = 'orig_0.mcap'
    pristine = (original / mcap_name).read_bytes()
    metadata = (original / 'metadata.yaml').read_bytes()
    rng = random.Random(SEED)
    failures: list[str] = []
    codes = {'check': [0, 0], 'reindex': [0, 0]}
    salvaged = 0
    detected = 0
    logging.getLogger('smarticle_bags').setLevel(logging.ERROR)
    try:
        for index in range(MUTATIONS):
            what, data = mutate(pristine, rng, index)
            bag = tmp_path / 'bag'
            shutil.rmtree(bag, ignore_errors=True)
            shutil.rmtree(tmp_path / 'bag.repaired', ignore_errors=True)
            bag.mkdir()
            (bag / 'bag_0.mcap').write_bytes(data)
            (bag / 'metadata.yaml').write_bytes(metadata.replace(b'orig_0', b'bag_0'))
            try:
                code = _main(['check', str(bag)])
                if code not in (0, 2):
                    failures.append(f'{what}: check exit {code}')
                    continue
                codes['check'][code // 2] += 1
                detected += code == 2
                try:  # the analysis input (columnar) on the damaged bag: what it returns is intact
                    reader = BagReader(bag)
                    poses = arrays.read_poses(reader)
                    joints = arrays.read_robot_topic(reader, 'joint_states')
                except BagError:
                    pass
                else:
                    if not set(poses.stamp.tolist()) <= pose_stamps or len(poses.stamp) > len(pose_stamps):
                        failures.append(f'{what}: poses that were not in the original')
                    if any(len(series.stamp) > len(pose_stamps) for series in joints.values()):
                        failures.append(f'{what}: more joint states than written')
                if code == 0 and data != pristine:
                    # only mutations that change nothing the reader uses may pass the check
                    if {(m.topic, m.log_time, m.data) for m in BagReader(bag).messages()} != everything:
                        failures.append(f'{what}: check passed a bag whose messages changed')
                code = _main(['reindex', str(bag)])
                if code not in (0, 2):
                    failures.append(f'{what}: reindex exit {code}')
                    continue
                codes['reindex'][code // 2] += 1
                if code == 0:
                    out = tmp_path / 'bag.repaired' if (tmp_path / 'bag.repaired').is_dir() else bag
                    reader = BagReader(out, strict=True)
                    got = [(raw.topic, raw.log_time, raw.data) for raw in reader.messages()]
                    for topic, _, cdr in got:  # every salvaged message decodes (rosbags' decoder)
                        STORE.deserialize_cdr(cdr, reader.topics[topic].type)
                    if not set(got) <= everything or len(got) != len(set(got)):
                        failures.append(f'{what}: salvaged messages that were not in the original')
                    if len(got) != reader.info.message_count:
                        failures.append(f'{what}: {len(got)} decoded of {reader.info.message_count}')
                    salvaged += len(got)
                assert (bag / 'bag_0.mcap').read_bytes() == data, f'{what}: the original was changed'
            except Exception as err: # what the CLI must never let through
                failures.append(f'{what}: {type(err).__name__}: {err}')
    finally:
        logging.getLogger('smarticle_bags').setLevel(logging.NOTSET)
    print(f'\nfuzz: {MUTATIONS} mutations (seed {SEED}), tracebacks {len(failures)}, check exit 0/2: '
          f'{codes["check"][0]}/{codes["check"][1]}, reindex exit 0/2: {codes["reindex"][0]}/'
          f'{codes["reindex"][1]}, messages salvaged {salvaged} of {MUTATIONS * len(everything)}')
    assert not failures, '\n'.join(failures[:20])
    assert detected > MUTATIONS * 0.8

