"""A GPU peer for `cargo xtask bench mesh-sdf --peer "python3 scripts/peers/warp_mesh_sdf.py"`:
NVIDIA Warp's mesh queries (a BVH built on the GPU, `wp.Mesh`) baking the same grid's signed
distance field, one thread per voxel centre: the nearest point on the mesh, signed by the fast
winding number (`mesh_query_point_sign_winding_number`, threshold 0.5) or by the nearest face's
normal (`mesh_query_point_sign_normal`).

Reads the mesh the bench wrote (`--mesh`: u32 vertex count, u32 triangle count, f32 xyz per
vertex, u32 three per triangle, little-endian), bakes `--reps` times per method after warm-up,
each timed with CUDA events around the BVH build and the query kernel together ("bake") and the
query kernel alone, and prints for each method one line

    ROW <method>|<median ms>|<min ms>|<max ms>|<query median ms>|<field file>

with the field (f32 per voxel, x fastest, world units, negative inside) written next to --out.
Beyond `--band` voxels (with `--band`; 0 for none) a query finds no face and the voxel holds
+band, unsigned, as a narrow-band bake would leave it.
"""

import argparse
import ctypes
import struct
import time

import numpy as np
import warp as wp


@wp.kernel
def bake(
    mesh: wp.uint64,
    origin: wp.vec3,
    voxel: float,
    nx: int,
    ny: int,
    max_dist: float,
    winding: int,
    out: wp.array(dtype=float),
):
    tid = wp.tid()
    x = tid % nx
    y = (tid // nx) % ny
    z = tid // (nx * ny)
    p = origin + wp.vec3(float(x) + 0.5, float(y) + 0.5, float(z) + 0.5) * voxel
    found = bool(False)
    sign = float(0.0)
    face = int(0)
    u = float(0.0)
    v = float(0.0)
    if winding == 1:
        q = wp.mesh_query_point_sign_winding_number(mesh, p, max_dist, 2.0, 0.5)
        found = q.result
        sign = q.sign
        face = q.face
        u = q.u
        v = q.v
    else:
        r = wp.mesh_query_point_sign_normal(mesh, p, max_dist, 1.0e-3)
        found = r.result
        sign = r.sign
        face = r.face
        u = r.u
        v = r.v
    if found:
        c = wp.mesh_eval_position(mesh, face, u, v)
        out[tid] = sign * wp.length(c - p)
    else:
        out[tid] = max_dist


class Stamps:
    """CUDA events on Warp's stream through the driver API (Warp 1.0 has no elapsed time), or
    wall time after a synchronize where there is no CUDA."""

    def __init__(self, device):
        self.device = device
        self.cu = None
        if device.startswith("cuda"):
            self.cu = ctypes.CDLL("libcuda.so.1")
            self.stream = ctypes.c_void_p(wp.get_stream(device).cuda_stream)

    def mark(self):
        if self.cu is None:
            wp.synchronize_device(self.device)
            return time.perf_counter()
        e = ctypes.c_void_p()
        assert self.cu.cuEventCreate(ctypes.byref(e), 0) == 0
        assert self.cu.cuEventRecord(e, self.stream) == 0
        return e

    def ms(self, a, b):
        if self.cu is None:
            return (b - a) * 1e3
        assert self.cu.cuEventSynchronize(b) == 0
        t = ctypes.c_float()
        assert self.cu.cuEventElapsedTime(ctypes.byref(t), a, b) == 0
        return t.value


def read_mesh(path):
    with open(path, "rb") as f:
        nv, nt = struct.unpack("<II", f.read(8))
        points = np.frombuffer(f.read(12 * nv), dtype="<f4").reshape(nv, 3)
        indices = np.frombuffer(f.read(12 * nt), dtype="<u4")
    return points, indices


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--origin", required=True, help="x,y,z of the grid's lowest corner")
    ap.add_argument("--voxel", type=float, required=True)
    ap.add_argument("--size", required=True, help="nx,ny,nz")
    ap.add_argument("--band", type=float, default=0.0, help="voxels; 0: the whole grid")
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--methods", default="winding,normal", help="winding, normal or both")
    ap.add_argument("--out", required=True, help="prefix of the field files")
    a = ap.parse_args()
    wp.init()
    device = "cuda:0" if wp.is_cuda_available() else "cpu"
    points, indices = read_mesh(a.mesh)
    origin = wp.vec3(*[float(v) for v in a.origin.split(",")])
    nx, ny, nz = [int(v) for v in a.size.split(",")]
    n = nx * ny * nz
    diagonal = a.voxel * float(np.sqrt(nx * nx + ny * ny + nz * nz))
    max_dist = a.band * a.voxel if a.band > 0 else diagonal
    points_d = wp.array(points, dtype=wp.vec3, device=device)
    indices_d = wp.array(indices.astype(np.int32), dtype=int, device=device)
    out = wp.zeros(n, dtype=float, device=device)
    stamps = Stamps(device)
    methods = [("winding", "warp winding number", 1), ("normal", "warp normal", 0)]
    for key, name, winding in methods:
        if key not in a.methods.split(","):
            continue
        bakes, queries = [], []
        for rep in range(a.reps + 3):
            t0 = stamps.mark()
            mesh = wp.Mesh(points_d, indices_d, support_winding_number=winding == 1)
            t1 = stamps.mark()
            wp.launch(bake, dim=n, inputs=[mesh.id, origin, a.voxel, nx, ny, max_dist, winding, out],
                      device=device)
            t2 = stamps.mark()
            if rep >= 3:
                bakes.append(stamps.ms(t0, t2))
                queries.append(stamps.ms(t1, t2))
        path = f"{a.out}.{name.replace(' ', '_')}.f32"
        out.numpy().astype("<f4").tofile(path)
        print(f"ROW {name}|{np.median(bakes):.4f}|{min(bakes):.4f}|{max(bakes):.4f}|"
              f"{np.median(queries):.4f}|{path}", flush=True)


if __name__ == "__main__":
    main()
