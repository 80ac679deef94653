"""An XDMF time series written frame by frame, readable while it grows (ParaView, meshio).

NAME.xdmf holds the mesh (a Uniform grid) and a temporal collection of the frames written so
far, each with its time and its arrays (point data: one value per node; cell data: one per
cell). The arrays are in HDF5 files beside it: the mesh in NAME/mesh.h5, frame K in
NAME/K.h5, each written under a temporary name and renamed, and NAME.xdmf is rewritten
atomically after every frame: a run killed at any moment leaves a series of the frames it
finished, none half written. The layout is meshio's (`meshio.xdmf.TimeSeriesWriter`), so
`meshio.xdmf.TimeSeriesReader` and ParaView's XDMF readers read it. Written by one process
(rank 0 of a run, from gathered arrays).
"""
import os
from pathlib import Path

import numpy as np

from femcontact.io import WriteError, describe, make_dir, write_text_atomic

TOPOLOGY = {"line": ("Polyline", 2), "triangle": ("Triangle", 3), "tetra": ("Tetrahedron", 4)}
ATTRIBUTE = {1: "Scalar", 3: "Vector", 9: "Tensor"}  # by components per value


class XdmfSeries:
    """NAME.xdmf over `points` (N x 3, mm) and `cells` (M x k node indices) of `cell_type`
    ('line', 'triangle' or 'tetra'); `add` appends one frame."""

    def __init__(self, path, points, cells, cell_type: str):
        self.path = Path(path)
        self.folder = make_dir(self.path.with_suffix(""))
        self.n_points, self.n_cells = len(points), len(cells)
        self.cell_type = cell_type
        self._write_h5("mesh.h5", {"geometry": np.asarray(points, float),
                                   "topology": np.asarray(cells, np.int64)})
        self.frames = []  # (time, file name, {array name: (center, components)})
        self._write_xml()

    def add(self, time: float, point_data: dict, cell_data: dict) -> None:
        """Append a frame at `time` (s): arrays of N (point data) or M (cell data) rows, each a
        scalar, a vector of 3 or a tensor of 9 (3 x 3, row-major) components."""
        arrays, layout = {}, {}
        for center, data, rows in (("Node", point_data, self.n_points), ("Cell", cell_data, self.n_cells)):
            for name, values in data.items():
                values = np.asarray(values, float).reshape(rows, -1)
                if values.shape[1] not in ATTRIBUTE:
                    raise ValueError(f"{name}: {values.shape[1]} components; expected 1, 3 or 9")
                arrays[name], layout[name] = values, (center, values.shape[1])
        name = f"{len(self.frames):06d}.h5"
        self._write_h5(name, arrays)
        self.frames.append((float(time), name, layout))
        self._write_xml()

    def _write_h5(self, name: str, arrays: dict) -> None:
        import h5py

        path = self.folder / name
        temporary = path.with_name(f".{name}.{os.getpid()}.tmp")
        try:
            with h5py.File(temporary, "w") as h5:
                for key, values in arrays.items():
                    h5.create_dataset(key, data=values)
            os.replace(temporary, path)
        except OSError as error:
            temporary.unlink(missing_ok=True)
            raise WriteError(describe(error, path)) from None

    def _item(self, name: str, key: str, shape: tuple, number: str = "Float") -> str:
        dims = " ".join(map(str, shape))
        precision = ' Precision="8"' if number == "Float" else ""
        return (f'<DataItem DataType="{number}" Dimensions="{dims}" Format="HDF"{precision}>'
                f"{self.folder.name}/{name}:/{key}</DataItem>")

    def _write_xml(self) -> None:
        topology, per_cell = TOPOLOGY[self.cell_type]
        lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">',
                 "<Domain>", '<Grid Name="mesh" GridType="Uniform">',
                 f'<Topology TopologyType="{topology}" NumberOfElements="{self.n_cells}" NodesPerElement="{per_cell}">',
                 self._item("mesh.h5", "topology", (self.n_cells, per_cell), "Int"), "</Topology>",
                 '<Geometry GeometryType="XYZ">', self._item("mesh.h5", "geometry", (self.n_points, 3)), "</Geometry>",
                 "</Grid>", '<Grid Name="frames" GridType="Collection" CollectionType="Temporal">']
        for time, name, layout in self.frames:
            lines += ['<Grid Name="frame" GridType="Uniform">',
                      '<xi:include xpointer="xpointer(//Grid[@Name=&quot;mesh&quot;]/*[self::Topology or '
                      'self::Geometry])"/>', f'<Time Value="{time!r}"/>']
            for key, (center, components) in layout.items():
                rows = self.n_points if center == "Node" else self.n_cells
                lines += [f'<Attribute Name="{key}" AttributeType="{ATTRIBUTE[components]}" Center="{center}">',
                          self._item(name, key, (rows, components)), "</Attribute>"]
            lines.append("</Grid>")
        lines += ["</Grid>", "</Domain>", "</Xdmf>"]
        write_text_atomic(self.path, "\n".join(lines) + "\n", sync=False)
