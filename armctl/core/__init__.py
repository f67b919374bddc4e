"""The pure core: the protocol, the motion-time model and kinematics, the profile's model, the
streamer, the job engine and a checked job.

Strategy: everything here takes bytes, objects and a time value (``now``) and returns bytes or
decisions; nothing imports a clock, a thread, a port, a terminal or a process
(tests/test_layers.py holds every module to that).  Whoever hosts it — the host edge
(armctl/host), the bench's virtual time, the probe, a test — feeds it status frames and write
completions and carries out its ``Write`` / ``Wait`` / ``Done`` (armctl/core/actions.py).  With the
language (armctl/script, armctl/lint) it is the part of armctl that every behaviour is decided in,
so each can be tested in milliseconds.
"""
