"""Embree and Open3D, single thread, on the very rays of a fathom benchmark.

usage: python embree_rays.py DIR
DIR holds buildings.obj (the mesh, NED metres) and grid_rays.f64 (per ray: origin,
direction, max range as seven little-endian f64), as written by

    FATHOM_EXPORT_GRID_RAYS=DIR cargo bench -p fathom-experiments --bench map_aided -- map_aided_rays

(the 41 x 41 x 9 x 7 rays of one MGPMF update, in the coherent order: yaw slice, beam,
then the horizontal grid). Prints the best of five timed passes, ns per ray, and the hit
fraction, for Embree (embreex, rays in that order, each with its max range) and Open3D's
RaycastingScene (nthreads=1). Needs: pip install numpy embreex open3d.
"""
import sys
import time

import numpy as np


def load(folder):
    verts = []
    faces = []
    with open(f"{folder}/buildings.obj") as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(x) - 1 for x in line.split()[1:4]])
    rays = np.fromfile(f"{folder}/grid_rays.f64", dtype="<f8").reshape(-1, 7)
    return np.array(verts), np.array(faces, dtype=np.int64), rays


def best_of(passes, run):
    best = float("inf")
    out = None
    for _ in range(passes):
        start = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - start)
    return best, out


def main():
    verts, faces, rays = load(sys.argv[1])
    n = len(rays)
    origins = rays[:, 0:3].astype(np.float32)
    dirs = rays[:, 3:6].astype(np.float32)
    ranges = rays[:, 6].astype(np.float32)
    result = {"triangles": len(faces), "rays": n}
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, verts[faces].astype(np.float32))
    scene.run(origins[:1000], dirs[:1000], dists=ranges[:1000].copy())
    seconds, ids = best_of(5, lambda: scene.run(origins, dirs, dists=ranges.copy()))
    result["embree_ns_per_ray"] = seconds / n * 1e9
    result["embree_hit_fraction"] = float((ids >= 0).mean())
    try:
        import open3d as o3d

        o3d_scene = o3d.t.geometry.RaycastingScene()
        o3d_scene.add_triangles(
            o3d.core.Tensor(verts.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32))
        )
        tensor = o3d.core.Tensor(np.hstack([origins, dirs]))
        seconds, hit = best_of(5, lambda: o3d_scene.cast_rays(tensor, nthreads=1))
        t_hit = hit["t_hit"].numpy()
        result["open3d_ns_per_ray"] = seconds / n * 1e9
        result["open3d_hit_fraction"] = float((t_hit <= ranges).mean())
    except ImportError as e:
        result["open3d_error"] = repr(e)
    print(result)


if __name__ == "__main__":
    main()
