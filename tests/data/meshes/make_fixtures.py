#!/usr/bin/python3
"""Writes the mesh fixtures of tests/client/mesh_fixtures_test.cc with the real tools.

Run from this directory with Debian 12's python3-vtk9 (VTK 9.1), python3-meshio (5.x) and gmsh
(4.8); the files are committed so the tests need none of them. The mesh is the same everywhere:
a 2 x 3 x 1.5 box cut into 6 tetrahedra around its diagonal, two regions (tets 0-2 label 1,
tets 3-5 label 2), one boundary triangle and one vertex cell that readers must skip, point data
"value" = x + 10 y + 100 z. Every coordinate and value is exact in binary.
"""
import subprocess

import meshio
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


def write_legacy():
    for version in (42, 51):
        for binary in (False, True):
            writer = vtk.vtkUnstructuredGridWriter()
            writer.SetInputData(vtk_grid())
            writer.SetFileVersion(version)
            if binary:
                writer.SetFileTypeToBinary()
            kind = "binary" if binary else "ascii"
            writer.SetFileName(f"vtk9_legacy{version}_{kind}.vtk")
            writer.Write()
    # What 3D Slicer writes for a compressed model: version 4.2, BINARY, SPACE=LPS in the title.
    grid = vtk_grid(space="LPS")
    grid.GetFieldData().RemoveArray("SPACE")
    writer = vtk.vtkUnstructuredGridWriter()
    writer.SetInputData(grid)
    writer.SetFileVersion(42)
    writer.SetFileTypeToBinary()
    writer.SetHeader("3D Slicer output. SPACE=LPS")
    writer.SetFileName("slicer_lps.vtk")
    writer.Write()


def meshio_mesh(label_key, label_dtype=np.int64):
    # Same cell order as vtk_grid: tets 0-2, a triangle, tets 3-5, a vertex.
    cells = [("tetra", np.array(TETS[:3])), ("triangle", np.array([[0, 1, 3]])),
             ("tetra", np.array(TETS[3:])), ("vertex", np.array([[5]]))]
    labels = [np.array(l, dtype=label_dtype) for l in (LABELS[:3], [9], LABELS[3:], [9])]
    cell_data = {label_key: labels}
    if label_key == "gmsh:physical":
        cell_data["gmsh:geometrical"] = [np.array([1, 1, 1]), np.array([1]), np.array([2, 2, 2]),
                                         np.array([1])]
    point_data = {"value": np.array(VALUES)}
    if label_key == "gmsh:physical":
        # meshio's MSH 4.1 writer makes its $Entities from the entity of each node: corners 4
        # and 5 belong to region 2 only, the others to volume 1.
        point_data["gmsh:dim_tags"] = np.array([[3, 2] if i in (4, 5) else [3, 1]
                                                for i in range(len(CORNERS))])
    return meshio.Mesh(np.array(CORNERS), cells, point_data=point_data, cell_data=cell_data)


def write_meshio():
    meshio.write("meshio.vtu", meshio_mesh("region"))
    meshio.write("meshio_ascii.vtk", meshio_mesh("region"), binary=False)
    meshio.write("meshio_binary.vtk", meshio_mesh("region"), binary=True)
    # int32 labels: legacy VTK names them vtktypeint32.
    meshio.write("meshio_int32_ascii.vtk", meshio_mesh("region", np.int32), binary=False)
    meshio.write("meshio_int32_binary.vtk", meshio_mesh("region", np.int32), binary=True)
    for fmt, name in (("gmsh22", "meshio_22"), ("gmsh", "meshio_41")):
        for binary in (False, True):
            meshio.write(f"{name}_{'binary' if binary else 'ascii'}.msh",
                         meshio_mesh("gmsh:physical"), file_format=fmt, binary=binary)
    meshio.write("meshio.mesh", meshio_mesh("medit:ref"))
    meshio.write("meshio.meshb", meshio_mesh("medit:ref"))


GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
Coherence;
Physical Volume(5) = {1};
Physical Volume(7) = {2};
Mesh.MeshSizeMin = 0.5;
Mesh.MeshSizeMax = 0.5;
"""


def write_gmsh():
    # Two unit cubes side by side as physical volumes 5 and 7, meshed by Gmsh itself.
    with open("two_cubes.geo", "w") as f:
        f.write(GEO)
    for version in ("22", "41"):
        for binary in (False, True):
            out = f"gmsh_{version}_{'binary' if binary else 'ascii'}.msh"
            args = ["gmsh", "-3", "two_cubes.geo", "-format", f"msh{version}", "-o", out]
            if binary:
                args.append("-bin")
            subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    # Partitioned (4.1 only): the elements then name the partitioned entities of
    # $PartitionedEntities, which carry the physical tags.
    for binary in (False, True):
        out = f"gmsh_41_part2_{'binary' if binary else 'ascii'}.msh"
        args = ["gmsh", "-3", "two_cubes.geo", "-part", "2", "-format", "msh41", "-o", out]
        if binary:
            args.append("-bin")
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)


if __name__ == "__main__":
    write_vtu()
    write_legacy()
    write_meshio()
    write_gmsh()
