"""The compiled part of the package, pydem._libdem (cffi over libdem, pydem/_build_ffi.py), and
the shipped data the commands need, copied into the package as pydem/data (the campaign stores
with their cached nets, the example measurement files; pydem/shipped.py finds them).
Everything else is declared in pyproject.toml."""
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = ("campaigns", "measurements")


class BuildWithData(build_py):
    def run(self):
        super().run()
        src = Path(__file__).resolve().parent / "data"
        for sub in SHIPPED:
            if (src / sub).is_dir():  # an sdist without data builds a package without it
                shutil.copytree(src / sub, Path(self.build_lib) / "pydem" / "data" / sub, dirs_exist_ok=True)


setup(cffi_modules=["pydem/_build_ffi.py:ffibuilder"], cmdclass={"build_py": BuildWithData})
