#!/usr/bin/python3
"""Writes the mesh fixtures of tests/client/mesh_fixtures_test.cc with the real tools.

Run from this directory with Debian 12's python3-vtk9 (VTK 9.1), python3-meshio (5.x) and gmsh
(4.8); the files are committed so the tests need none of them. The mesh is the same everywhere:
a 2 x 3 x 1.5 box cut into 6 tetrahedra around its diagonal, two regions (tets 0-2 label 1,
tets 3-5 label 2), one boundary triangle and one vertex cell that readers must skip, point data
"value" = x + 10 y + 100 z. Every coordinate and value is exact in binary.
"""
import numpy as np
import vtk

CORNERS = [(x, y, z) for z in (0.0, 1.5) for y in (0.0, 3.0) for x in (0.0, 2.0)]
TETS = [(0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)]
LABELS = [1, 1, 1, 2, 2, 2]
VALUES = [x + 10 * y + 100 * z for (x, y, z) in CORNERS]


def vtk_grid(space=None):
    points = vtk.vtkPoints()
    points.SetDataTypeToDouble()
    for p in CORNERS:
        points.InsertNextPoint(p)
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    region = vtk.vtkIntArray()
    region.SetName("region")
    # Cell order: tets 0-2, the triangle, tets 3-5, the vertex.
    for t in TETS[:3]:
        grid.InsertNextCell(vtk.VTK_TETRA, 4, t)
        region.InsertNextValue(LABELS[TETS.index(t)])
    grid.InsertNextCell(vtk.VTK_TRIANGLE, 3, (0, 1, 3))
    region.InsertNextValue(9)
    for t in TETS[3:]:
        grid.InsertNextCell(vtk.VTK_TETRA, 4, t)
        region.InsertNextValue(LABELS[TETS.index(t)])
    grid.InsertNextCell(vtk.VTK_VERTEX, 1, (5,))
    region.InsertNextValue(9)
    grid.GetCellData().AddArray(region)
    value = vtk.vtkDoubleArray()
    value.SetName("value")
    for v in VALUES:
        value.InsertNextValue(v)
    grid.GetPointData().AddArray(value)
    if space:
        # As 3D Slicer writes it: coordinates in LPS, a "SPACE" string in field data.
        flipped = vtk.vtkPoints()
        flipped.SetDataTypeToDouble()
        for (x, y, z) in CORNERS:
            flipped.InsertNextPoint(-x, -y, z)
        grid.SetPoints(flipped)
        tag = vtk.vtkStringArray()
        tag.SetName("SPACE")
        tag.InsertNextValue(space)
        grid.GetFieldData().AddArray(tag)
    return grid


def write_vtu():
    modes = {"ascii": 0, "binary": 1, "appended": 2}
    compressors = {"none": 0, "zlib": 1, "lz4": 2, "lzma": 3}
    for mode, mode_code in modes.items():
        for name, code in compressors.items():
            if mode == "ascii" and name != "none":
                continue
            writer = vtk.vtkXMLUnstructuredGridWriter()
            writer.SetInputData(vtk_grid())
            writer.SetDataMode(mode_code)
            writer.SetCompressorType(code)
            writer.SetFileName(f"vtk9_{mode}_{name}.vtu")
            writer.Write()
    # Appended base64 with 32-bit headers; appended raw big-endian cannot be asked of VTK.
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetInputData(vtk_grid())
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOn()
    writer.SetHeaderTypeToUInt32()
    writer.SetCompressorTypeToZLib()
    writer.SetFileName("vtk9_appended_base64_uint32_zlib.vtu")
    writer.Write()
    # What 3D Slicer writes for a compressed model: appended raw zlib, SPACE=LPS in field data.
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetInputData(vtk_grid(space="LPS"))
    writer.SetDataModeToAppended()
    writer.SetCompressorTypeToZLib()
    writer.SetFileName("slicer_lps.vtu")
    writer.Write()


if __name__ == "__main__":
    write_vtu()
