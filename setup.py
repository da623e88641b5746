"""The compiled part of the package: pydem._libdem, cffi over libdem (pydem/_build_ffi.py).
Everything else is declared in pyproject.toml."""
from setuptools import setup

setup(cffi_modules=["pydem/_build_ffi.py:ffibuilder"])
