"""Trial data: the :class:`Trial`, units, readers and writers, validation (the front door)."""

from shipid.io.trial import CHANNELS, Trial
from shipid.io.files import parse_channel_map, read_trial, write_trial
from shipid.io.paths import data_root
from shipid.io.combine import concat_trials

__all__ = ["CHANNELS", "Trial", "read_trial", "write_trial", "parse_channel_map", "data_root",
           "concat_trials"]
