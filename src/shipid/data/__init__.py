"""Trial data: the :class:`Trial`, units, readers and writers, validation (the front door)."""

from shipid.data.trial import CHANNELS, Trial
from shipid.data.io import parse_channel_map, read_trial, write_trial
from shipid.data.paths import data_root
from shipid.data.combine import concat_trials

__all__ = ["CHANNELS", "Trial", "read_trial", "write_trial", "parse_channel_map", "data_root",
           "concat_trials"]
