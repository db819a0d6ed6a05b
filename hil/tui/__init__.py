"""The shop-floor terminal app (Textual) for calibration campaigns.

`hil.tui.app.create_app` builds the app for both ``hil tui`` and the tests; `hil.tui.session` holds
everything that talks to the station, the store and the engine (always off the UI thread), so the
screens only present what the session reports through the messages in `hil.tui.messages`.

May import everything below it in hil; only the CLI (``hil tui``) imports it. Screens reach the app
through `hil.tui.screens.base.AppHandle`, never by importing `hil.tui.app`.
"""

from hil.tui.app import HilApp, TuiOptions, create_app

__all__ = ["HilApp", "TuiOptions", "create_app"]
