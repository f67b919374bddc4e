"""``armctl plot``: see the path a job takes before it runs.

Modules, one job each:
  path.py     pure: a compiled job → segments of sampled points (line, kind, text) and findings
  style.py    colours and legend names shared by both renderers
  html.py     plotly: one self-contained interactive HTML file (needs the plot extra)
  static.py   matplotlib: SVG/PNG, three orthographic views or one (needs the plot extra)
  command.py  the click command, registered by armctl/ui/cli.py

Only path.py and style.py may be imported without the plot extra.
"""
