"""The parameters of the recorder and player nodes in one place, and the configs built from them.

The ``smarticle-bag record/play`` flags are these parameters under ``ros2 bag``'s flag names, with
the same defaults (the CLI reads them from here). ``config/recorder.yaml`` and
``config/player.yaml`` ship the defaults (a test keeps them equal). No ROS import.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from smarticle_common.params import ParamSpec

from .errors import OptionError
from .playback import PlaybackOptions
from .selection import TopicFilter, parse_remaps, split_names
from .writer import STORAGE_PRESETS, Compression, WriterOptions

RECORDER_NODE = 'recorder'
PLAYER_NODE = 'player'

RECORDER_PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('output', '', 'bag folder to create; empty = rosbag2_YYYY_MM_DD-HH_MM_SS in the working dir'),
    ParamSpec('topics', '', 'topics to record, separated by spaces or commas'),
    ParamSpec('all', False, 'record every topic (re-scanned while recording)'),
    ParamSpec('regex', '', 'also record topics matching this regular expression (re.search)'),
    ParamSpec('exclude_regex', '', 'never record topics matching this regular expression'),
    ParamSpec('include_hidden_topics', False, 'let -a/-e match hidden topics (a name part starting with _)'),
    ParamSpec('storage_preset_profile', 'none',
              'none, fastwrite (no compression), zstd_fast, zstd_small, lz4'),
    ParamSpec('compression_format', '', 'chunk compression zstd, lz4 or none; overrides the preset when set'),
    ParamSpec('chunk_size', 0, 'mcap chunk size in bytes; 0 = the preset (1 MiB, 4 MiB for zstd_small)',
              0, 2**31),
    ParamSpec('max_bag_size', 0, 'split into a new .mcap after this many bytes; 0 = never', 0, 2**62),
    ParamSpec('max_bag_duration', 0.0, 'split into a new .mcap after this many seconds; 0 = never', 0.0, 1e9),
    ParamSpec('flush_interval', 1.0, 'close the open chunk at least this often (s): what a crash can lose',
              0.01, 3600.0),
    ParamSpec('topic_polling_interval', 0.5, 'how often new topics are looked for (s)', 0.01, 60.0),
    ParamSpec('topic_wait_warning', 5.0, 'warn when a named topic has not appeared after this many s',
              0.0, 3600.0),
)

PLAYER_PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('bag', '', 'bag folder or .mcap file to play'),
    ParamSpec('topics', '', 'play only these topics (spaces or commas); empty = all'),
    ParamSpec('remap', '', 'remappings /old:=/new, separated by spaces or commas'),
    ParamSpec('rate', 1.0, 'playback speed factor (> 0; 2.0 = twice as fast)', 1e-6, 1e6),
    ParamSpec('loop', False, 'start again at the end'),
    ParamSpec('start_offset', 0.0, 'start this many seconds after the first message', 0.0, 1e12),
    ParamSpec('playback_duration', 0.0, 'play only this many seconds of bag time; 0 = to the end', 0.0, 1e12),
    ParamSpec('start_paused', False, 'wait for a resume (~/pause false, or space) before publishing'),
    ParamSpec('clock', 0.0, 'publish /clock at this rate in Hz from bag time; 0 = no /clock', 0.0, 10000.0),
    ParamSpec('delay', 0.0, 'wait this many seconds after start-up (discovery) before playing', 0.0, 3600.0),
)


def default(specs: tuple[ParamSpec, ...], name: str) -> Any:
    """Return the default of parameter ``name``."""
    return next(s.default for s in specs if s.name == name)


@dataclass(frozen=True)
class RecorderConfig:
    """Everything the recorder needs: output folder, topic choice, writer options and timers."""

    output: Path
    filter: TopicFilter
    writer: WriterOptions
    flush_interval: float
    polling_interval: float
    wait_warning: float


def default_bag_name(now: float | None = None) -> str:
    """Return rosbag2's default bag folder name, ``rosbag2_YYYY_MM_DD-HH_MM_SS``."""
    return time.strftime('rosbag2_%Y_%m_%d-%H_%M_%S', time.localtime(now))


def writer_options(preset: str, compression: str, chunk_size: int, max_size: int,
                   max_duration: float) -> WriterOptions:
    """Build WriterOptions from a storage preset, an optional compression and split limits."""
    if preset not in STORAGE_PRESETS:
        raise OptionError(f'unknown storage preset {preset!r}; choose one of {", ".join(STORAGE_PRESETS)}')
    chosen, preset_chunk = STORAGE_PRESETS[preset]
    if compression:
        try:
            chosen = Compression(compression.lower())
        except ValueError:
            raise OptionError(
                f'unknown compression format {compression!r}; choose zstd, lz4 or none') from None
    return WriterOptions(compression=chosen, chunk_size=chunk_size or preset_chunk, max_bag_size=max_size,
                         max_bag_duration=round(max_duration * 1e9))


def recorder_config(values: dict[str, Any]) -> RecorderConfig:
    """Build the recorder config from checked parameter values."""
    topic_filter = TopicFilter(topics=split_names(values['topics']), regex=values['regex'],
                               exclude_regex=values['exclude_regex'], all=values['all'],
                               include_hidden=values['include_hidden_topics'])
    return RecorderConfig(
        output=Path(values['output'] or default_bag_name()), filter=topic_filter,
        writer=writer_options(values['storage_preset_profile'], values['compression_format'],
                              values['chunk_size'], values['max_bag_size'], values['max_bag_duration']),
        flush_interval=values['flush_interval'], polling_interval=values['topic_polling_interval'],
        wait_warning=values['topic_wait_warning'])


@dataclass(frozen=True)
class PlayerConfig:
    """Everything the player needs: bag, timing options, topic filter and remappings."""

    bag: Path
    options: PlaybackOptions
    topics: tuple[str, ...]
    remaps: dict[str, str]


def player_config(values: dict[str, Any]) -> PlayerConfig:
    """Build the player config from checked parameter values."""
    if not values['bag']:
        raise OptionError('no bag given: set the bag parameter (smarticle-bag play BAG)')
    options = PlaybackOptions(rate=values['rate'], loop=values['loop'], start_offset=values['start_offset'],
                              playback_duration=values['playback_duration'],
                              start_paused=values['start_paused'],
                              clock=values['clock'], delay=values['delay'])
    return PlayerConfig(bag=Path(values['bag']), options=options, topics=split_names(values['topics']),
                        remaps=parse_remaps([values['remap']]))
