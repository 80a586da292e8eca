"""The arena: every controller on every arm, ranked against its own floor (:mod:`.leaderboard`)."""

from adaptive_dd.arena.leaderboard import COLUMNS, DEFAULT_CONTROLLERS, leaderboard, shipped_scenarios

__all__ = ["COLUMNS", "DEFAULT_CONTROLLERS", "leaderboard", "shipped_scenarios"]
