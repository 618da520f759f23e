#!/usr/bin/python3
"""The out-of-sample cases of docs/results/unseen_cases.md: eleven volumes and meshes unlike the
reproduction's (tools/reproduce), made by an independent helper on 2026-11-28 to check the
schemes on data they were not tuned on.

    python3 tools/unseen_cases/make_cases.py OUT_DIR [DATA_DIR [TETREFINE]] [-- CASE ...]

writes OUT_DIR/<case>/{vol.nii.gz, mesh.vtu, volume.npy, case.json}: the volume as NIfTI (what
`tetrefine refine --volume` reads), the mesh in world millimetres (ascii .vtu, positively
oriented), and the Plaza peer's inputs (bench/peers/plaza_refine.py: volume.npy is the NIfTI
read back, x fastest). DATA_DIR holds the real volumes (default ../shared/data); TETREFINE is
the CLI, for case D's block mesh (default build/client/tetrefine). Needs numpy, nibabel, meshio,
gmsh and tetgen (Debian: python3-nibabel python3-meshio gmsh tetgen).
"""
import json, os, subprocess, sys
import numpy as np, nibabel as nib, meshio

args = sys.argv[1:]
cases_asked = args[args.index('--') + 1:] if '--' in args else []
args = args[:args.index('--')] if '--' in args else args
if not args:
    sys.exit(__doc__)
ROOT = os.path.abspath(args[0])
DATA = os.path.abspath(args[1] if len(args) > 1 else '../shared/data')
TETREFINE = os.path.abspath(args[2] if len(args) > 2 else 'build/client/tetrefine')
rng = np.random.default_rng(12345)

def save_volume(d, arr, spacing, origin=(0, 0, 0), dtype=None):
    """arr indexed [i,j,k] (x,y,z); positive diagonal affine."""
    os.makedirs(d, exist_ok=True)
    if dtype is not None:
        arr = arr.astype(dtype)
    aff = np.diag(list(spacing) + [1.0]); aff[:3, 3] = origin
    img = nib.Nifti1Image(arr, aff)
    img.header.set_data_dtype(arr.dtype)
    img.header.set_slope_inter(1.0, 0.0)
    nib.save(img, os.path.join(d, 'vol.nii.gz'))
    back = np.asarray(nib.load(os.path.join(d, 'vol.nii.gz')).get_fdata(), dtype=np.float64)
    np.save(os.path.join(d, 'volume.npy'), np.ascontiguousarray(back.transpose(2, 1, 0)))
    json.dump({'origin': list(map(float, origin)), 'spacing': list(map(float, spacing)),
               'norm_coeff': float(back.max() - back.min())}, open(os.path.join(d, 'case.json'), 'w'))
    lo = np.array(origin, float); hi = lo + (np.array(arr.shape) - 1) * np.array(spacing)
    return lo, hi

def orient(p, t):
    a, b, c, d = (p[t[:, i]] for i in range(4))
    v = np.einsum('ij,ij->i', b - a, np.cross(c - a, d - a))
    t = t.copy(); f = v < 0; t[f, 2], t[f, 3] = t[f, 3].copy(), t[f, 2].copy()
    assert (np.abs(v) > 0).all()
    return t

def write_mesh(d, p, t):
    used = np.unique(t); remap = np.full(len(p), -1); remap[used] = np.arange(len(used))
    p = p[used]; t = remap[t]
    t = orient(p, t)
    meshio.write(os.path.join(d, 'mesh.vtu'), meshio.Mesh(p, [('tetra', t)]), binary=False)
    print(d, 'tets', len(t), 'verts', len(p))

def gmsh_mesh(d, geo_body, size):
    geo = os.path.join(d, 'm.geo')
    open(geo, 'w').write('SetFactory("OpenCASCADE");\n' + geo_body +
                         f'\nMesh.MeshSizeMax = {size};\nMesh.MeshSizeMin = {size}*0.5;\n')
    subprocess.run(['gmsh', geo, '-3', '-format', 'msh22', '-o', os.path.join(d, 'm.msh')],
                   check=True, stdout=subprocess.DEVNULL)
    m = meshio.read(os.path.join(d, 'm.msh'))
    return m.points.astype(np.float64), m.cells_dict['tetra'].astype(np.int64)

def box_inset(lo, hi, spacing, f=0.25):
    s = np.array(spacing); return lo + f * s, hi - f * s

def gmsh_box(d, lo, hi, size):
    e = hi - lo
    return gmsh_mesh(d, f'Box(1) = {{{lo[0]},{lo[1]},{lo[2]}, {e[0]},{e[1]},{e[2]}}};', size)

def gmsh_ellipsoid(d, lo, hi, size):
    c = (lo + hi) / 2; r = (hi - lo) / 2
    body = (f'Sphere(1) = {{0,0,0, 1}};\nDilate {{{{0,0,0}}, {{{r[0]},{r[1]},{r[2]}}}}} {{ Volume{{1}}; }}\n'
            f'Translate {{{c[0]},{c[1]},{c[2]}}} {{ Volume{{1}}; }}')
    return gmsh_mesh(d, body, size)

def tetgen_box(d, lo, hi, q, a):
    x0, y0, z0 = lo; x1, y1, z1 = hi
    pts = [(x0,y0,z0),(x1,y0,z0),(x1,y1,z0),(x0,y1,z0),(x0,y0,z1),(x1,y0,z1),(x1,y1,z1),(x0,y1,z1)]
    faces = [(1,2,3,4),(5,6,7,8),(1,2,6,5),(2,3,7,6),(3,4,8,7),(4,1,5,8)]
    f = os.path.join(d, 'box.poly')
    with open(f, 'w') as o:
        o.write('8 3 0 0\n' + ''.join(f'{i+1} {p[0]!r} {p[1]!r} {p[2]!r}\n' for i, p in enumerate(pts)))
        o.write('6 0\n' + ''.join(f'1\n4 {a_} {b} {c} {e}\n' for a_, b, c, e in faces) + '0\n0\n')
    subprocess.run(['tetgen', f'-pq{q}a{a}Q', f], check=True)
    nodes = np.loadtxt(os.path.join(d, 'box.1.node'), skiprows=1, comments='#')
    ele = np.loadtxt(os.path.join(d, 'box.1.ele'), skiprows=1, comments='#', dtype=np.int64)
    idx = {int(n): i for i, n in enumerate(nodes[:, 0])}
    t = np.vectorize(idx.get)(ele[:, 1:5])
    return nodes[:, 1:4], t

def canon(name):
    img = nib.as_closest_canonical(nib.load(os.path.join(DATA, name)))
    return np.asarray(img.get_fdata()), np.abs(np.diag(img.affine)[:3])

def blur(a, s):
    # separable gaussian via FFT-free convolution
    k = np.arange(-int(3*s)-1, int(3*s)+2); g = np.exp(-k**2/(2*s*s)); g /= g.sum()
    for ax in range(3):
        a = np.apply_along_axis(lambda v: np.convolve(np.pad(v, len(k)//2, mode='edge'), g, 'valid'), ax, a)
    return a

def shepp_logan(N):
    """The 3-D Kak-Slaney Shepp-Logan phantom (10 ellipsoids: value, semi-axes, centre, angle
    about z in degrees) sampled on N^3 points of [-1, 1]^3, indexed [x, y, z]."""
    x = np.linspace(-1, 1, N); X, Y, Z = np.meshgrid(x, x, x, indexing='ij')
    E = [(2, .69, .92, .9, 0, 0, 0, 0), (-.8, .6624, .874, .88, 0, 0, 0, 0),
         (-.2, .41, .16, .21, -.22, 0, -.25, 108), (-.2, .31, .11, .22, .22, 0, -.25, 72),
         (.2, .21, .25, .5, 0, .35, -.25, 0), (.2, .046, .046, .046, 0, .1, -.25, 0),
         (.1, .046, .023, .02, -.08, -.65, -.25, 0), (.1, .046, .023, .02, .06, -.65, -.25, 90),
         (.2, .056, .04, .1, .06, -.105, .625, 90), (-.2, .056, .056, .1, 0, .1, .625, 0)]
    v = np.zeros_like(X)
    for A, a, b, c, x0, y0, z0, ph in E:
        th = np.deg2rad(ph); xr = (X-x0)*np.cos(th) + (Y-y0)*np.sin(th); yr = -(X-x0)*np.sin(th) + (Y-y0)*np.cos(th)
        v[(xr/a)**2 + (yr/b)**2 + ((Z-z0)/c)**2 <= 1] += A
    return v

def want(n): return not cases_asked or n in cases_asked

# A t1crop: T1 canonical, crop, gmsh box
if want('A_t1crop'):
    d = f'{ROOT}/A_t1crop'; v, sp = canon('t1_brain_128x128x62.nii.gz')
    v = v[32:96, 10:52, 30:94]
    lo, hi = save_volume(d, v, sp, (10, 20, 30), np.int16)
    print('A shape', v.shape, sp)
    p, t = gmsh_box(d, *box_inset(lo, hi, sp), 5.0); write_mesh(d, p, t)

# B t1half: T1 canonical, 2x2x2 block means, gmsh ellipsoid
if want('B_t1half'):
    d = f'{ROOT}/B_t1half'; v, sp = canon('t1_brain_128x128x62.nii.gz')
    n = np.array(v.shape) // 2 * 2; v = v[:n[0], :n[1], :n[2]]
    v = v.reshape(n[0]//2, 2, n[1]//2, 2, n[2]//2, 2).mean(axis=(1, 3, 5))
    sp2 = sp * 2; lo, hi = save_volume(d, v, sp2, (0, 0, 0), np.float32)
    print('B shape', v.shape, sp2)
    p, t = gmsh_ellipsoid(d, *box_inset(lo, hi, sp2, 0.5), 10.0); write_mesh(d, p, t)

# C epi_diag: EPI samples with a diagonal 4x4x5 affine, tetgen box
if want('C_epidiag'):
    d = f'{ROOT}/C_epidiag'; v = np.asarray(nib.load(os.path.join(DATA, 'epi_brain_58x58x24.nii.gz')).dataobj)
    sp = (4.0, 4.0, 5.0); lo, hi = save_volume(d, v, sp, (-100, -100, -50), np.int16)
    p, t = tetgen_box(d, *box_inset(lo, hi, sp), 1.4, 400.0); write_mesh(d, p, t)

# D t1mask: the whole T1 volume (canonical), `tetrefine mesh --block 3 --mask-threshold 50`
if want('D_t1mask'):
    d = f'{ROOT}/D_t1mask'; v, sp = canon('t1_brain_128x128x62.nii.gz')
    save_volume(d, v, sp, (0, 0, 0), np.int16)
    subprocess.run([TETREFINE, 'mesh', '--volume', os.path.join(d, 'vol.nii.gz'), '--block', '3',
                    '--mask-threshold', '50', '--output', os.path.join(d, 'block.vtu')],
                   check=True)
    m = meshio.read(os.path.join(d, 'block.vtu'))
    write_mesh(d, m.points.astype(np.float64), m.cells_dict['tetra'].astype(np.int64))

# E shepp3d: 3-D Shepp-Logan (Kak-Slaney ellipsoids, step edges), 64^3, 1 mm, float32, gmsh box
if want('E_shepp'):
    d = f'{ROOT}/E_shepp'; N = 64
    v = shepp_logan(N)
    sp = (1.0, 1.0, 1.0); lo, hi = save_volume(d, v, sp, (0, 0, 0), np.float32)
    print('E range', v.min(), v.max())
    p, t = gmsh_box(d, *box_inset(lo, hi, sp), 4.0); write_mesh(d, p, t)

# F noisysphere: uint8 40^3, sphere 200 on 20, gaussian noise sd 4, gmsh ball
if want('F_noisysphere'):
    d = f'{ROOT}/F_noisysphere'; N = 40
    i = np.arange(N); X, Y, Z = np.meshgrid(i, i, i, indexing='ij'); r = np.sqrt((X-19.5)**2 + (Y-19.5)**2 + (Z-19.5)**2)
    v = np.where(r < 13, 200.0, 20.0) + rng.normal(0, 4, r.shape)
    v = np.clip(np.round(v), 0, 255)
    sp = (1.0, 1.0, 1.0); lo, hi = save_volume(d, v, sp, (0, 0, 0), np.uint8)
    p, t = gmsh_ellipsoid(d, *box_inset(lo, hi, sp, 0.5), 2.5); write_mesh(d, p, t)

# G vessel: smooth gradient + thin bright curved tube (gaussian profile, sd 0.6 mm), 64^3 at 0.5 mm, float32, tetgen box
if want('G_vessel'):
    d = f'{ROOT}/G_vessel'; N = 64; h = 0.5
    i = np.arange(N) * h; X, Y, Z = np.meshgrid(i, i, i, indexing='ij')
    base = 100 + 2.0 * X + 1.0 * Y + 0.5 * Z
    s = np.linspace(0, 1, 400); cx = 16 + 8 * np.sin(2*np.pi*s); cy = 16 + 8 * np.cos(2*np.pi*s) * 0.6; cz = 2 + 28 * s
    dist2 = np.full(X.shape, np.inf)
    for a, b, c in zip(cx, cy, cz):
        dist2 = np.minimum(dist2, (X-a)**2 + (Y-b)**2 + (Z-c)**2)
    v = base + 300 * np.exp(-dist2 / (2 * 0.6**2))
    sp = (h, h, h); lo, hi = save_volume(d, v, sp, (0, 0, 0), np.float32)
    print('G range', v.min(), v.max())
    p, t = tetgen_box(d, *box_inset(lo, hi, sp), 1.4, 2.0); write_mesh(d, p, t)

# H aniso: 0.7 x 0.7 x 3 mm, 96x96x20, int16, blurred ellipsoid blobs; the SfePy unit cube mesh scaled in
if want('H_aniso'):
    d = f'{ROOT}/H_aniso'; sp = (0.7, 0.7, 3.0); n = (96, 96, 20)
    X, Y, Z = np.meshgrid(*(np.arange(k) * s for k, s in zip(n, sp)), indexing='ij')
    v = np.full(X.shape, 50.0)
    for (x0, y0, z0, rx, ry, rz, val) in [(33, 33, 28, 20, 25, 20, 400), (40, 30, 30, 6, 6, 12, 900), (20, 45, 20, 4, 8, 9, -300)]:
        v[((X-x0)/rx)**2 + ((Y-y0)/ry)**2 + ((Z-z0)/rz)**2 <= 1] += val
    v = blur(v, 1.0)
    lo, hi = save_volume(d, v, sp, (-30, -30, 0), np.int16)
    m = meshio.read(os.path.join(DATA, 'unit_cube_1782tets.mesh'))
    lo2, hi2 = box_inset(lo, hi, sp)
    p = lo2 + (m.points + 0.5) * (hi2 - lo2)
    write_mesh(d, p, m.cells_dict['tetra'].astype(np.int64))

# I ct_int16: CT-like int16 -1024..~2500, 64x64x48 at 1x1x1.5 mm, gmsh box (fine)
if want('I_ct'):
    d = f'{ROOT}/I_ct'; sp = (1.0, 1.0, 1.5); n = (64, 64, 48)
    X, Y, Z = np.meshgrid(*(np.arange(k) * s for k, s in zip(n, sp)), indexing='ij')
    c = np.array([31.5, 31.5, 35.25])
    body = ((X-c[0])/28)**2 + ((Y-c[1])/22)**2 <= 1
    v = np.full(X.shape, -1024.0); v[body] = 40
    lung = (((X-c[0]-12)/9)**2 + ((Y-c[1])/13)**2 + ((Z-c[2])/30)**2 <= 1) | (((X-c[0]+12)/9)**2 + ((Y-c[1])/13)**2 + ((Z-c[2])/30)**2 <= 1)
    v[lung] = -850
    rr = ((X-c[0])/25)**2 + ((Y-c[1])/19)**2
    v[(rr >= 0.85) & (rr <= 1.0) & body] = 1200
    v[((X-c[0])**2 + (Y-c[1]+17)**2) <= 16] = 2500  # spine
    v = v + rng.normal(0, 15, v.shape)
    lo, hi = save_volume(d, v, sp, (0, 0, 0), np.int16)
    p, t = gmsh_box(d, *box_inset(lo, hi, sp), 3.0); write_mesh(d, p, t)

# J anatcrop: anatomical canonical crop, gmsh ellipsoid (coarse)
if want('J_anatcrop'):
    d = f'{ROOT}/J_anatcrop'; v, sp = canon('anatomical_33x41x25.nii')
    v = v[4:29, 5:36, 3:22]
    lo, hi = save_volume(d, v, sp, (-20, -25, -5), np.int16)
    p, t = gmsh_ellipsoid(d, *box_inset(lo, hi, sp, 0.5), 6.0); write_mesh(d, p, t)

# K shepp32: the same Shepp-Logan ellipsoids sampled on 32^3 at 2 mm, float32, gmsh box size 6
if want('K_shepp32'):
    d = f'{ROOT}/K_shepp32'; N = 32
    v = shepp_logan(N)
    sp = (2.0, 2.0, 2.0); lo, hi = save_volume(d, v, sp, (0, 0, 0), np.float32)
    p, t = gmsh_box(d, *box_inset(lo, hi, sp), 6.0); write_mesh(d, p, t)
