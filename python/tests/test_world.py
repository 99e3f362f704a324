"""fathom.World: the batch cast against the caster's scalar call and a brute-force
numpy triangle test, file readers and bad inputs."""

import numpy as np
import pytest

import fathom

DATA = "crates/fathom-map/tests/data"


def brute_force(world, origins, dirs, max_range=np.inf):
    """Closest hit of each ray by testing every triangle (Moller-Trumbore, numpy)."""
    v = world.vertices[world.triangles]  # (T, 3, 3)
    a, e1, e2 = v[:, 0], v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    d = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    ranges = np.full(len(origins), np.inf)
    tri = np.full(len(origins), -1)
    for i, (o, di) in enumerate(zip(origins, d)):
        p = np.cross(di, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-300
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = o - a
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        w = (q @ di) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 1e-9) & (t <= max_range)
        if hit.any():
            j = int(np.argmin(np.where(hit, t, np.inf)))
            ranges[i], tri[i] = t[j], j
    return ranges, tri


@pytest.fixture(scope="module")
def house(root):
    return fathom.World.from_obj(
        root / DATA / "house.obj",
        origin_offset=(325000.0, 4150000.0, 0.0),
        materials={"concrete": 2, "roof_tiles": fathom.MATERIAL_OTHER_BASE + 1},
    )


def rays_at_triangles(world, rng, count):
    """Rays from outside the bounds to random interior points of random triangles."""
    v = world.vertices[world.triangles]
    lo, hi = world.bounds
    pick = rng.integers(0, len(v), count)
    bary = rng.dirichlet([2.0, 2.0, 2.0], count)
    targets = np.einsum("ij,ijk->ik", bary, v[pick])
    center, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    dirs_out = rng.standard_normal((count, 3))
    origins = center + radius * dirs_out / np.linalg.norm(dirs_out, axis=1, keepdims=True)
    return origins, targets - origins


def test_cast_matches_the_scalar_caster_and_brute_force(house, root):
    rng = np.random.default_rng(11)
    o1, d1 = rays_at_triangles(house, rng, 600)
    o2 = rng.uniform(-60, 60, (400, 3))  # random rays, many miss
    d2 = rng.standard_normal((400, 3))
    origins, dirs = np.vstack([o1, o2]), np.vstack([d1, d2])
    hits = house.cast(origins, dirs, 500.0)
    assert len(hits) == 1000 and hits.hit[:600].all() and not hits.hit[600:].all()
    for i in range(len(origins)):
        one = house.cast_one(tuple(origins[i]), tuple(dirs[i]), 500.0)
        if one is None:
            assert not hits.hit[i] and hits.ranges[i] == np.inf
            assert np.isnan(hits.normals[i]).all() and hits.materials[i] == fathom.MATERIAL_MISS
            assert hits.triangles[i] == -1
        else:
            r, n, m, t = one
            assert (r, m, t) == (hits.ranges[i], hits.materials[i], hits.triangles[i])
            assert np.array_equal(n, hits.normals[i])
    ranges, tri = brute_force(house, origins, dirs, 500.0)
    assert np.array_equal(np.isfinite(ranges), hits.hit)
    assert np.allclose(ranges[hits.hit], hits.ranges[hits.hit], rtol=1e-9, atol=1e-9)
    assert np.array_equal(tri, hits.triangles)
    # normals are unit, face the ray, and are normal to the hit triangle
    h = hits.hit
    d = dirs[h] / np.linalg.norm(dirs[h], axis=1, keepdims=True)
    assert np.allclose(np.linalg.norm(hits.normals[h], axis=1), 1.0)
    assert (np.einsum("ij,ij->i", hits.normals[h], d) <= 0).all()
    v = house.vertices[house.triangles[hits.triangles[h]]]
    assert np.allclose(np.einsum("ij,ij->i", hits.normals[h], v[:, 1] - v[:, 0]), 0, atol=1e-9)
    # materials are the hit triangle's
    assert np.array_equal(hits.materials[h], house.materials[hits.triangles[h]])
    assert set(np.unique(house.materials)) == {1, 2, 3}
    # negative control: a shorter range cuts hits
    short = house.cast(origins, dirs, 5.0)
    assert short.hit.sum() < hits.hit.sum()


def test_thread_count_does_not_change_the_result(house):
    rng = np.random.default_rng(5)
    o, d = rays_at_triangles(house, rng, 20000)
    a = house.cast(o, d, threads=1)
    b = house.cast(o, d)
    for name in ("ranges", "materials", "triangles", "hit"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.normals, b.normals, equal_nan=True)


def test_stl_binary_and_ascii_and_arrays(root):
    a = fathom.World.from_stl(root / DATA / "wedge_binary.stl")
    b = fathom.World.from_stl(root / DATA / "wedge_ascii.stl", material="glass")
    assert len(a) == len(b) > 0 and np.array_equal(a.vertices, b.vertices)
    assert set(b.materials) == {fathom.MATERIAL_GLASS}
    rng = np.random.default_rng(3)
    o, d = rays_at_triangles(a, rng, 200)
    ha, hb = a.cast(o, d), b.cast(o, d)
    assert np.array_equal(ha.ranges, hb.ranges) and ha.hit.all()
    assert a.report["faces_read"] > 0
    # one triangle from arrays, in NED: the plane z = 5 below the origin
    w = fathom.World.from_arrays(
        [[-10, -10, 5], [10, -10, 5], [0, 10, 5]], [[0, 1, 2]], materials=[fathom.MATERIAL_GLASS]
    )
    h = w.cast([[0, 0, 0], [0, 0, 0]], [[0, 0, 2], [0, 0, -1]])
    assert h.ranges[0] == 5.0 and h.hit.tolist() == [True, False]
    assert h.normals[0].tolist() == [0.0, 0.0, -1.0] and h.materials[0] == fathom.MATERIAL_GLASS
    assert w.report is None


def test_bad_inputs_raise(house, root, tmp_path):
    ok = np.zeros((2, 3))
    down = np.array([[0, 0, 1.0], [1, 0, 0]])
    with pytest.raises(ValueError, match=r"origins: expected shape \(N, 3\), got \(2, 2\)"):
        house.cast(np.zeros((2, 2)), down)
    with pytest.raises(ValueError, match="origins: expected an"):
        house.cast(np.zeros((2, 3, 1)), down)
    with pytest.raises(ValueError, match="origins has 2 rows but directions has 1"):
        house.cast(ok, down[:1])
    with pytest.raises(ValueError, match=r"origins: row 1 is not finite \(NaN\)"):
        house.cast(np.array([[0, 0, 0], [np.nan, 0, 0]]), down)
    with pytest.raises(ValueError, match="directions: row 0 is zero"):
        house.cast(ok, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="directions: row 1 is not finite"):
        house.cast(ok, np.array([[0, 0, 1], [0, np.inf, 0]]))
    for bad in (0.0, -1.0, np.nan):
        with pytest.raises(ValueError, match="max_range: entry 0 must be > 0"):
            house.cast(ok, down, bad)
    with pytest.raises(ValueError, match=r"max_range: expected a number or shape \(2,\)"):
        house.cast(ok, down, np.ones(3))
    with pytest.raises(ValueError, match="threads must be at least 1"):
        house.cast(ok, down, threads=0)
    with pytest.raises(FileNotFoundError):
        fathom.World.from_obj(tmp_path / "missing.obj")
    # unknown usemtl name: the reader's error names the file and the line
    with pytest.raises(ValueError, match=r"house.obj`: OBJ line 10: unknown material `Concrete`"):
        fathom.World.from_obj(root / DATA / "house.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n")
    with pytest.raises(ValueError, match="line 3"):
        fathom.World.from_obj(bad)
    with pytest.raises(ValueError, match="axes"):
        fathom.World.from_stl(root / DATA / "wedge_binary.stl", axes="up")
    with pytest.raises(ValueError, match="scale"):
        fathom.World.from_stl(root / DATA / "wedge_binary.stl", scale=-1.0)
    trunc = tmp_path / "trunc.stl"
    trunc.write_bytes((root / DATA / "wedge_binary.stl").read_bytes()[:-7])
    with pytest.raises(ValueError, match="face"):
        fathom.World.from_stl(trunc)
    with pytest.raises(ValueError, match="triangles: row 0 has the index 0.5"):
        fathom.World.from_arrays(np.eye(3), [[0.5, 1, 2]])
    with pytest.raises(ValueError):
        fathom.World.from_arrays(np.eye(3), [[0, 1, 7]])
