"""nn: torch networks and their export — the MLP per bulk property trained with scaled conjugate
gradient (mlp, scg), its export to libdem's weights files and to C (export), seed 001's image
networks (cnn) and their training loop (training). A leaf: nothing here imports pydem
(tests/py/test_layering.py)."""
