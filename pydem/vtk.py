"""Time series for ParaView: each call writes the particles and every mesh wall as .vtu files
(libdem's dem_vtk_write_*) and keeps one .pvd collection per series up to date, so a run that is
stopped half-way still leaves a series ParaView opens (File > Open > particles.pvd).

    series = VtkSeries("out/vtk")
    series.write(domain)        # particles_00000.vtu, mesh0_00000.vtu, particles.pvd, mesh0.pvd
"""
from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import quoteattr


class VtkSeries:
    def __init__(self, directory: str | os.PathLike):
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.entries: dict[str, list[tuple[float, str]]] = {}

    def write(self, d) -> list[Path]:
        """One time step of the domain; returns the .vtu files written."""
        k = len(self.entries.get("particles", []))
        files = {"particles": f"particles_{k:05d}.vtu"}
        files.update({f"mesh{m}": f"mesh{m}_{k:05d}.vtu" for m in range(d.mesh_wall_count)})
        d.write_vtk(self.dir / files["particles"])
        for m in range(d.mesh_wall_count):
            d.write_mesh_vtk(m, self.dir / files[f"mesh{m}"])
        for series, name in files.items():
            self.entries.setdefault(series, []).append((d.time, name))
            self._collection(series)
        return [self.dir / f for f in files.values()]

    def _collection(self, series: str):
        rows = "".join(f'  <DataSet timestep="{t!r}" part="0" file={quoteattr(f)}/>\n' for t, f in self.entries[series])
        text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0">\n<Collection>\n'
                f"{rows}</Collection>\n</VTKFile>\n")
        tmp = self.dir / f".{series}.pvd.tmp"
        tmp.write_text(text)
        os.replace(tmp, self.dir / f"{series}.pvd")  # a reader never sees half a collection
