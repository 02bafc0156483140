"""Exceptions of smarticle_bags: each names the bag, file or option that was wrong and what to do."""

from __future__ import annotations


class BagError(Exception):
    """Base class of every error raised by smarticle_bags."""


class BagNotFoundError(BagError, FileNotFoundError):
    """The bag path does not exist."""


class MetadataError(BagError):
    """A bag folder without a usable metadata.yaml."""


class CorruptBagError(BagError):
    """An .mcap file that is truncated, has no valid footer or holds damaged chunks."""


class BagExistsError(BagError, FileExistsError):
    """The output folder of a recording exists already."""


class MessageDefinitionError(BagError):
    """A message type whose .msg definition cannot be found or parsed."""


class TopicSelectionError(BagError, ValueError):
    """A topic name, regular expression or remapping that is invalid or matches nothing."""


class OptionError(BagError, ValueError):
    """A recording or playback option that makes no sense (a rate <= 0, a negative duration...)."""


class CsvImportError(BagError, ValueError):
    """A CSV of tracks that cannot be imported: ``problems`` holds one line per bad row or column."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__('\n'.join(problems))
        self.problems = list(problems)
