"""Seed 001's study: hopper frames to discharge time and remaining-particle ratio.

The hopper rig draws the frames (pydem.rigs.frames); this package stores them (store), runs the
Table 1 frame set (cli `frames`), weighs the Table 1 parameters by grey relational analysis (gra),
trains and judges the image networks of nn.cnn (frame_data, experiments) beside the physics
baselines and image gauges (baselines), and writes the report (report). `pydem images ...` and
`python -m pydem.seed001 ...` are its command line (docs/seed001.md). Nothing here is imported by
the rest of pydem except that command's hook (command.py); the networks need torch (the `[nn]`
extra)."""
