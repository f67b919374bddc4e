"""The host edge: ports, clocks, threads and files around the pure core, and the Python API.

Strategy: thin.  ``link`` opens a port and reads status frames; ``driver`` carries out an
engine's ``Write`` / ``Wait`` / ``Done`` on a link (``virtual_wait`` moves a virtual clock
through the simulator's ``next_event_s`` / ``advance_to`` instead of sleeping); ``runner`` is a
job's host on it; ``jobflow`` and ``arm_worker`` are a job's steps on the arm; ``api`` is ``Arm``,
whose worker thread owns the port.  A job's data only goes down from here — to the core and the
port — and nothing here calls up into a user interface (tests/test_layers.py).
"""
