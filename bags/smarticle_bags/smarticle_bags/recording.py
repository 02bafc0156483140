"""Record a bag of a run from a launcher: the recorder as one more process of a ``ProcessGroup``.

Used by ``bags/scripts/make_samples.py``, the bag benchmarks and the demo::

    from smarticle_bags.recording import start_recording

    with ProcessGroup(log_dir, env) as group:
        ...                                            # gait nodes
        rec = start_recording(group, out / 'bag', ['/smarticles/poses', '/clock'])
        bridge = group.start('sim_bridge', ..., '-p', 'wait_for_subscribers:=2')
        rec.wait_subscribed(timeout=20.0)              # optional: every named topic has a subscription
        ...                                            # wait for the bridge to finish
        info = rec.stop()                              # SIGINT: the bag is closed with a footer

The recorder is the ``smarticle-bag record`` process itself (a separate process talking over DDS), so
what it stores is what any other node receives. No rclpy import here.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from .errors import BagError
from .metadata import BagInfo


@dataclass
class Recording:
    """A running ``smarticle-bag record`` process of a ProcessGroup and the bag it writes."""

    group: Any
    proc: subprocess.Popen[bytes]
    output: Path
    topics: tuple[str, ...]
    _info: BagInfo | None = field(default=None, repr=False)

    def subscribed(self) -> set[str]:
        """Topics the recorder has subscribed to so far (from its log)."""
        return set(re.findall(r'subscribed to (\S+) \(', self.group.output(self.proc)))

    def wait_subscribed(self, topics: Iterable[str] | None = None, timeout: float = 20.0) -> bool:
        """Wait until the recorder subscribed to ``topics`` (default: the named ones); False on timeout."""
        wanted = set(self.topics if topics is None else topics)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if wanted <= self.subscribed():
                return True
            if self.proc.poll() is not None:
                raise BagError(f'the recorder exited with code {self.proc.returncode}:\n'
                               + self.group.output(self.proc)[-2000:])
            time.sleep(0.05)
        return wanted <= self.subscribed()

    def stop(self, timeout: float = 20.0) -> BagInfo:
        """Stop the recorder with SIGINT (the bag gets its footer) and return the bag's metadata.

        Raises BagError if the recorder fails or does not stop within ``timeout`` seconds (it is then
        killed; the bag stays readable up to its last flushed chunk).
        """
        from .metadata import read_metadata

        if self._info is not None:
            return self._info
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
            raise BagError(f'the recorder did not stop within {timeout:g} s and was killed; '
                           f'run "smarticle-bag reindex {self.output}"') from None
        if code != 0:
            raise BagError(f'the recorder exited with code {code}:\n' + self.group.output(self.proc)[-2000:])
        self._info = read_metadata(self.output)
        return self._info


def start_recording(group: Any, output: Path | str, topics: Iterable[str] = (), *, regex: str = '',
                    compression: str = '', flush_interval: float = 1.0, polling_interval: float = 0.1,
                    ros_args: Iterable[str] = ()) -> Recording:
    """Start ``smarticle-bag record`` in ``group`` (a smarticle_common.launching.ProcessGroup).

    ``topics`` are recorded as soon as a publisher offers them (looked for every ``polling_interval``
    s); ``regex`` adds topics by regular expression; ``compression`` is '' (the default, zstd), 'zstd',
    'lz4' or 'none'; ``ros_args`` go after ``--ros-args`` (e.g. ``['-p', 'use_sim_time:=true']``).
    ``output`` must not exist yet. Stop the returned Recording with ``stop()``.
    """
    output = Path(output)
    names = tuple(topics)
    if not names and not regex:
        raise BagError('start_recording: give topics and/or a regex')
    args = ['record', *names, '-o', str(output), '--flush-interval', f'{flush_interval:g}',
            '--polling-interval', f'{polling_interval:g}']
    if regex:
        args += ['-e', regex]
    if compression:
        args += ['--compression-format', compression]
    extra = list(ros_args)
    if extra:
        args += ['--ros-args', *extra]
    proc = group.start('smarticle-bag', *args)
    return Recording(group, proc, output, names)
