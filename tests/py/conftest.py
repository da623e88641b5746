"""pytest set-up: the repository root on sys.path (so `import pydem` works without the .pth)."""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
