"""`python -m pydem` (the `pydem` command): see pydem/cli.py."""
import sys

from .cli import main

sys.exit(main())
