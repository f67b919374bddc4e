"""The user interfaces of the command line: the ``armctl`` command (``cli``, click wiring only)
and what it shows — the live panels, the run's JSON events, the decoded status, the output
formats.  Each is a client of the host edge's public API (``Arm``) and of the core's values;
nothing below calls into here."""
