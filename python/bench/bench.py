"""Side-by-side timings of fathom's Python bindings (docs/performance.md):

1. fathom.KalmanFilter vs FilterPy's KalmanFilter: one predict + update of the same
   6/3 constant-velocity problem (same matrices, same measurements);
2. fathom.World.cast vs Open3D's RaycastingScene.cast_rays: 10^6 rays on the same
   mesh (a procedural city: terrain grid plus box buildings), one thread and all
   threads, with the agreement of the two casters' hits.

Not a test: run it by hand (python python/bench/bench.py [--rays N] [--json FILE]).
Needs numpy, filterpy and open3d (open3d needs libusb-1.0-0 on Debian).
"""

import argparse
import json
import os
import platform
import resource
import statistics
import time

import numpy as np

import fathom


def cpu_seconds():
    """CPU time of this process (all threads), s."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def best_of(fn, repeats, cpu=None):
    """Per-call wall seconds of fn (which returns its own call count): median and best.
    With a dict `cpu`, also the median per-call CPU seconds (all threads) in cpu["s"]:
    on a loaded machine, CPU < wall shows the process did not get its cores."""
    times, cpus = [], []
    for _ in range(repeats):
        c0, t0 = cpu_seconds(), time.perf_counter()
        calls = fn()
        times.append((time.perf_counter() - t0) / calls)
        cpus.append((cpu_seconds() - c0) / calls)
    if cpu is not None:
        cpu["s"] = statistics.median(cpus)
    return statistics.median(times), min(times)


def kalman(steps, repeats):
    from filterpy.kalman import KalmanFilter as FilterPyKF

    dt, qa = 0.1, 0.5
    F = np.eye(6)
    F[:3, 3:] = dt * np.eye(3)
    Q = np.zeros((6, 6))
    for i in range(3):
        Q[i, i] = qa * dt**4 / 4
        Q[i, i + 3] = Q[i + 3, i] = qa * dt**3 / 2
        Q[i + 3, i + 3] = qa * dt**2
    H = np.hstack([np.eye(3), np.zeros((3, 3))])
    R = 0.25 * np.eye(3)
    zs = np.random.default_rng(1).normal(size=(steps, 3, 1))

    def make(cls):
        kf = cls(6, 3)
        kf.F, kf.Q, kf.H, kf.R = F.copy(), Q.copy(), H.copy(), R.copy()
        kf.P = 10.0 * np.eye(6)
        return kf

    def loop(cls):
        def run():
            kf = make(cls)
            for z in zs:
                kf.predict()
                kf.update(z)
            return steps
        return run

    out = {}
    for name, cls in (("fathom", fathom.KalmanFilter), ("filterpy", FilterPyKF)):
        med, best = best_of(loop(cls), repeats)
        out[name] = {"median_us": med * 1e6, "best_us": best * 1e6}
    a, b = make(fathom.KalmanFilter), make(FilterPyKF)
    for z in zs[:1000]:
        a.predict(); a.update(z)
        b.predict(); b.update(z)
    out["max_abs_diff_x_after_1000_steps"] = float(np.max(np.abs(a.x - b.x)))
    out["steps_per_repeat"] = steps
    return out


def city(grid=300, spacing=1.0, buildings=400, seed=3):
    """A terrain heightfield (grid x grid quads) with box buildings, NED metres."""
    rng = np.random.default_rng(seed)
    n = grid + 1
    xs, ys = np.meshgrid(np.arange(n) * spacing, np.arange(n) * spacing, indexing="ij")
    zs = -2.0 * np.sin(xs / 37.0) * np.cos(ys / 23.0)  # down is +z: gentle hills
    verts = [np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)]
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = [np.stack([a, b, c], 1), np.stack([a, c, d], 1)]
    base = n * n
    size = grid * spacing
    for _ in range(buildings):
        x0, y0 = rng.uniform(0, size - 12, 2)
        w, l, h = rng.uniform(4, 12), rng.uniform(4, 12), rng.uniform(5, 40)
        corners = np.array([[x0 + dx, y0 + dy, z] for z in (2.0, -h) for dx, dy in ((0, 0), (w, 0), (w, l), (0, l))])
        verts.append(corners)
        box = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6],
                        [3, 0, 4], [3, 4, 7], [4, 5, 6], [4, 6, 7]]) + base
        tris.append(box)
        base += 8
    return np.vstack(verts), np.vstack(tris)


def raycast(rays, repeats):
    import open3d as o3d

    vertices, triangles = city()
    world = fathom.World.from_arrays(vertices, triangles)
    rng = np.random.default_rng(9)
    lo, hi = vertices.min(0), vertices.max(0)
    origins = np.column_stack([rng.uniform(lo[0], hi[0], rays), rng.uniform(lo[1], hi[1], rays),
                               np.full(rays, -60.0)])
    dirs = rng.normal(size=(rays, 3))
    dirs[:, 2] = np.abs(dirs[:, 2]) + 0.2  # downwards, some grazing
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)

    mesh = o3d.t.geometry.TriangleMesh()
    mesh.vertex.positions = o3d.core.Tensor(world.vertices.astype(np.float32))
    mesh.triangle.indices = o3d.core.Tensor(world.triangles.astype(np.int32))
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(mesh)
    o3d_rays = o3d.core.Tensor(np.hstack([origins, dirs]).astype(np.float32))
    scene.cast_rays(o3d_rays[:1000])  # build the BVH before timing

    threads = os.cpu_count() or 1
    out = {"rays": rays, "triangles": len(world), "threads_all": threads}
    for label, n in (("1_thread", 1), ("all_threads", None)):
        def f_fathom(n=n):
            world.cast(origins, dirs, threads=n)
            return rays
        def f_o3d(n=n):
            scene.cast_rays(o3d_rays, nthreads=1 if n == 1 else 0)
            return rays
        for name, fn in (("fathom", f_fathom), ("open3d", f_o3d)):
            cpu = {}
            med, best = best_of(fn, repeats, cpu)
            out[f"{name}_{label}"] = {"median_s": med * rays, "best_s": best * rays,
                                      "cpu_s": cpu["s"] * rays, "mrays_per_s": 1e-6 / med}
    ours = world.cast(origins, dirs)
    theirs = scene.cast_rays(o3d_rays)
    t = theirs["t_hit"].numpy().astype(np.float64)
    both = ours.hit & np.isfinite(t)
    out["hit_agreement"] = float(np.mean(ours.hit == np.isfinite(t)))
    out["same_triangle"] = float(np.mean(ours.triangles[both] == theirs["primitive_ids"].numpy()[both]))
    out["max_range_diff_m_same_triangle"] = float(np.max(np.abs(ours.ranges[both] - t[both])))
    out["hits"] = int(ours.hit.sum())
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rays", type=int, default=1_000_000)
    p.add_argument("--kf-steps", type=int, default=20_000)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--json", help="also write the results here")
    args = p.parse_args()
    import filterpy
    import open3d

    res = {
        "machine": {"cpus": os.cpu_count(), "load_average_1min_at_start": os.getloadavg()[0], "python": platform.python_version(),
                    "numpy": np.__version__, "fathom": fathom.__version__,
                    "filterpy": filterpy.__version__, "open3d": open3d.__version__},
        "kalman_6_3": kalman(args.kf_steps, args.repeats),
        "raycast": raycast(args.rays, args.repeats),
    }
    print(json.dumps(res, indent=2))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=2)


if __name__ == "__main__":
    main()
