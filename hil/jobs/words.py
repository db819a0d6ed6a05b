"""How a job speaks to the operator while it runs, without printing: a `Say` callback.

The command line prints each line as ``hil: <text>`` on stderr; the terminal app shows it as a notice
of that severity. One wording for both, written here once.
"""

from __future__ import annotations

from collections.abc import Callable

#: ``say(text, severity)``; severity is "information", "warning" or "error".
Say = Callable[[str, str], None]


def quiet(text: str, severity: str = "information") -> None:
    """A `Say` that drops everything (a caller that reports nothing)."""


def outage_words(say: Say) -> Callable[[str | None], None]:
    """The store's ``on_outage`` hook in words: a lost database link makes the run wait (the arm stands
    at its pose) until it is back (`reason` None)."""

    def outage(reason: str | None) -> None:
        if reason is None:
            say("database link back; the run continues", "information")
        else:
            say(f"{reason}; the arm waits at its pose", "warning")

    return outage


def simulated_store_words(location: object, plant_env: bool) -> str:
    """What a simulated station's job says of its store: its campaigns are kept apart from real ones
    (`hil.store.paths`), where, and how to list them or choose another. `plant_env`: ``$HIL_DB`` is
    set (and not used)."""
    plant = "the real stations' store ($HIL_DB)" if plant_env else "the real stations' store"
    return (f"simulated station: its campaigns go to {location}, not to {plant}; `hil history --db "
            f"{location}` lists them, --db chooses another store")
