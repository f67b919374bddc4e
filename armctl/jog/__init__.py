"""``armctl jog``: keyboard jogging with a dead-man switch, step jog, and teaching poses.

Pure core, thin edge — one job per module:

  keys.py       raw terminal bytes → key events (escape sequences split across reads, lone Esc)
  keymap.py     which key does what; the default map and armctl.toml's [jog.keys]
  settings.py   dead-man timings and speed levels; armctl.toml's [jog]
  deadman.py    continuous jog: which joystick frames to send, and when (time passed in)
  moves.py      step and gripper moves from the reported pose; when a move has arrived
  teach.py      a reported pose as a G1 / G6 line
  session.py    keys + status → frames + taught lines: the whole behaviour, no I/O
  view.py       the rich panel (pure render)
  terminal.py   raw mode, restored on every exit path; SIGTERM/SIGHUP; reading stdin
  edge.py       the loop: select on stdin, the link, the log, the record file, the Live panel
  command.py    the click command ``jog``
"""
