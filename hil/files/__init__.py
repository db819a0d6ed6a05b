"""Users' files in and hil's files out: the one reader and the one writer every command uses.

* `inputs` — reading a user's file (config, model, program, table) with one-line errors for a missing,
  unreadable, directory or non-UTF-8 path;
* `outputs` — writing a result whole or not at all (temporary file + rename), and CSV text.

May import: `hil.errors` only. Everything else in hil may import this.
"""
