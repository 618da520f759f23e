"""The README demo from Python: python3 refine_demo.py HOST:PORT OUT.vtu (a tetrefine_server)."""
import pathlib, sys, meshio, nibabel, tetrefine
examples = pathlib.Path(__file__).resolve().parent.parent
volume = tetrefine.volume_from_nibabel(nibabel.load(examples / "anatomical_33x41x25.nii"))
mesh = tetrefine.mesh_from_meshio(meshio.read(examples / "unit_cube_1782tets.mesh"))
points = tetrefine.fit_to_volume(mesh.points, volume)  # as refine --fit-mesh-to-volume does
with tetrefine.Client(sys.argv[1]) as client:
    result = client.refine(volume.data, volume.spacing, volume.origin, points, mesh.tets, 0.1,
                           labels=mesh.labels,  # the cube's Medit refs: two regions
                           on_iteration=lambda s: print(s.iteration, s.final_tets, s.max_error))
print(result.stop_reason, result.points.shape, result.tets.shape, result.lattice.max_error)
result.to_meshio(label_name="medit:ref").write(sys.argv[2])  # + value, iteration, quality
