"""Trial data: the :class:`Trial`, units, readers and writers, validation (the front door)."""

from shipid.data.trial import CHANNELS, Trial

__all__ = ["CHANNELS", "Trial"]
