//! `fathom.World`: a triangle mesh in local NED metres (from an OBJ or STL file, or
//! from arrays) with the BVH caster of `fathom-map`, and `World.cast`: numpy rays in,
//! numpy hits out, cast in parallel (rayon, chunks of rays through the caster's batch
//! call; each ray's result depends on that ray only, so the output is the same for any
//! thread count).
//!
//! Misses: range `inf`, normal `NaN`, material [`MATERIAL_MISS`] (-1), triangle -1,
//! `hit` False. Materials are integer codes: [`MATERIAL_OPAQUE`] (0),
//! [`MATERIAL_GLASS`] (1), and `Other(id)` as [`MATERIAL_OTHER_BASE`] + id.
//! Bad rays (a non-finite origin or direction, a zero direction, a `max_range` that is
//! NaN or `<= 0`) raise `ValueError` naming the row, before anything is cast.

use std::path::PathBuf;

use fathom_core::{Material, Ray, RayCaster, RayHit};
use fathom_map::{AxisConvention, BvhCaster, ImportReport, ImportSettings, MaterialTable, TriMesh};
use nalgebra::Vector3;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rayon::prelude::*;

use crate::arrays::{points, shape_text};

/// Material code of a miss.
pub const MATERIAL_MISS: i32 = -1;
/// Material code of `Opaque`.
pub const MATERIAL_OPAQUE: i32 = 0;
/// Material code of `Glass`.
pub const MATERIAL_GLASS: i32 = 1;
/// `Other(id)` has the code `MATERIAL_OTHER_BASE + id`.
pub const MATERIAL_OTHER_BASE: i32 = 2;

/// Rays per task of the parallel cast.
const CHUNK: usize = 4096;

fn material_code(m: Material) -> i32 {
    match m {
        Material::Opaque => MATERIAL_OPAQUE,
        Material::Glass => MATERIAL_GLASS,
        Material::Other(id) => MATERIAL_OTHER_BASE + i32::from(id),
    }
}

fn material_from_code(code: i64) -> PyResult<Material> {
    match code {
        0 => Ok(Material::Opaque),
        1 => Ok(Material::Glass),
        c if (2..=2 + i64::from(u16::MAX)).contains(&c) => {
            Ok(Material::Other(u16::try_from(c - 2).unwrap_or(u16::MAX)))
        }
        c => Err(PyValueError::new_err(format!(
            "material code {c}: expected 0 (opaque), 1 (glass) or 2 + id (other, id <= 65535)"
        ))),
    }
}

/// A material given as `"opaque"`, `"glass"` or an integer code.
fn material_arg(obj: &Bound<'_, PyAny>) -> PyResult<Material> {
    if let Ok(s) = obj.extract::<String>() {
        return match s.to_ascii_lowercase().as_str() {
            "opaque" => Ok(Material::Opaque),
            "glass" => Ok(Material::Glass),
            _ => Err(PyValueError::new_err(format!(
                "material {s:?}: expected \"opaque\", \"glass\" or an integer code"
            ))),
        };
    }
    material_from_code(obj.extract::<i64>()?)
}

fn axes_arg(axes: &str) -> PyResult<AxisConvention> {
    match axes {
        "ned" => Ok(AxisConvention::Ned),
        "enu" | "enu_z_up" => Ok(AxisConvention::EnuZUp),
        "y_up_rh" | "y_up_right_handed" => Ok(AxisConvention::YUpRightHanded),
        "y_up_lh" | "y_up_left_handed" => Ok(AxisConvention::YUpLeftHanded),
        _ => Err(PyValueError::new_err(format!(
            "axes {axes:?}: expected \"ned\", \"enu_z_up\", \"y_up_right_handed\" or \
             \"y_up_left_handed\" (the names of a scenario's `world.axes`; short forms \
             \"enu\", \"y_up_rh\", \"y_up_lh\")"
        ))),
    }
}

fn read_file(path: &PathBuf) -> PyResult<Vec<u8>> {
    std::fs::read(path).map_err(|e| {
        let msg = format!("cannot read `{}`: {e}", path.display());
        if e.kind() == std::io::ErrorKind::NotFound {
            PyFileNotFoundError::new_err(msg)
        } else {
            PyOSError::new_err(msg)
        }
    })
}

/// The rays of `cast`: origins, directions and ranges checked (module rules).
fn rays(
    origins: &Bound<'_, PyAny>,
    directions: &Bound<'_, PyAny>,
    max_range: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Ray>> {
    let o = points("origins", origins)?;
    let d = points("directions", directions)?;
    if o.len() != d.len() {
        return Err(PyValueError::new_err(format!(
            "origins has {} rows but directions has {}",
            o.len(),
            d.len()
        )));
    }
    let ranges: Vec<f64> = match max_range.map(|m| (m, m.extract::<f64>())) {
        None => vec![f64::INFINITY; o.len()],
        Some((_, Ok(r))) => vec![r; o.len()],
        Some((m, Err(_))) => {
            let (shape, values) = crate::arrays::any_shape("max_range", m)?;
            if shape.as_slice() != [o.len()] {
                return Err(PyValueError::new_err(format!(
                    "max_range: expected a number or shape ({},), got {}",
                    o.len(),
                    shape_text(&shape)
                )));
            }
            values
        }
    };
    let mut out = Vec::with_capacity(o.len());
    for (i, ((o, d), r)) in o.iter().zip(&d).zip(&ranges).enumerate() {
        if *d == [0.0; 3] {
            return Err(PyValueError::new_err(format!(
                "directions: row {i} is zero"
            )));
        }
        // NaN fails too
        if r.is_nan() || *r <= 0.0 {
            return Err(PyValueError::new_err(format!(
                "max_range: entry {i} must be > 0 (inf: no limit), got {r}"
            )));
        }
        out.push(Ray::new(Vector3::from(*o), Vector3::from(*d), *r));
    }
    Ok(out)
}

/// The hits of `World.cast`, one entry per ray (misses: see the module docs).
#[pyclass(module = "fathom", frozen, get_all)]
pub struct RayHits {
    /// Range along the unit direction, m, float64 `(N,)`; `inf` for a miss.
    ranges: Py<PyAny>,
    /// Unit normal of the hit triangle facing the ray, NED, float64 `(N, 3)`; `NaN`
    /// for a miss.
    normals: Py<PyAny>,
    /// Material code, int32 `(N,)`; `MATERIAL_MISS` (-1) for a miss.
    materials: Py<PyAny>,
    /// Index of the hit triangle in `World.triangles`, int64 `(N,)`; -1 for a miss.
    triangles: Py<PyAny>,
    /// Whether the ray hit, bool `(N,)`.
    hit: Py<PyAny>,
    len: usize,
}

#[pymethods]
impl RayHits {
    fn __len__(&self) -> usize {
        self.len
    }

    fn __repr__(&self) -> String {
        format!("fathom.RayHits({} rays)", self.len)
    }
}

/// A triangle mesh in local NED metres with a BVH ray caster.
#[pyclass(module = "fathom", frozen)]
pub struct World {
    mesh: TriMesh,
    caster: BvhCaster,
    report: Option<ImportReport>,
}

impl World {
    fn new(mesh: TriMesh, report: Option<ImportReport>) -> Self {
        let caster = BvhCaster::new(&mesh);
        Self {
            mesh,
            caster,
            report,
        }
    }
}

fn settings(
    axes: &str,
    scale: f64,
    origin_offset: [f64; 3],
    default_material: Option<Material>,
) -> PyResult<ImportSettings> {
    Ok(ImportSettings {
        axes: axes_arg(axes)?,
        scale,
        origin_offset,
        default_material,
        ..ImportSettings::default()
    })
}

#[pymethods]
impl World {
    /// Reads a Wavefront OBJ file into local NED metres.
    ///
    /// `axes`: the file's axes, as a scenario's `world.axes` names them:
    /// `"enu_z_up"` (x east, y north, z up; default), `"ned"`, `"y_up_right_handed"`
    /// (Blender/glTF) or `"y_up_left_handed"` (Unity); the short forms `"enu"`,
    /// `"y_up_rh"`, `"y_up_lh"` are accepted too; `scale`: metres per file
    /// unit; `origin_offset`: subtracted from every file point first (file axes and
    /// units); `materials`: `usemtl` name -> `"opaque"`, `"glass"` or a material code
    /// (the names `opaque` and `glass` are always known; an unknown name is an
    /// error); `default_material`: the material of faces before any `usemtl` (`None`:
    /// such faces are an error).
    #[staticmethod]
    #[pyo3(signature = (path, axes="enu_z_up", scale=1.0, origin_offset=(0.0, 0.0, 0.0), materials=None, default_material=Some("opaque".to_string())))]
    fn from_obj(
        py: Python<'_>,
        path: PathBuf,
        axes: &str,
        scale: f64,
        origin_offset: (f64, f64, f64),
        materials: Option<&Bound<'_, PyDict>>,
        default_material: Option<String>,
    ) -> PyResult<Self> {
        let default_material = default_material
            .map(|m| material_arg(&m.into_pyobject(py)?.into_any()))
            .transpose()?;
        let mut s = settings(
            axes,
            scale,
            [origin_offset.0, origin_offset.1, origin_offset.2],
            default_material,
        )?;
        let mut table = MaterialTable::default();
        if let Some(m) = materials {
            for (k, v) in m.iter() {
                table.insert(&k.extract::<String>()?, material_arg(&v)?);
            }
        }
        s.materials = table;
        let bytes = read_file(&path)?;
        let label = path.display().to_string();
        let (mesh, report) = py
            .detach(|| fathom_map::obj::parse_obj(&bytes, &s))
            .map_err(|e| PyValueError::new_err(e.in_file(label).to_string()))?;
        Ok(py.detach(|| Self::new(mesh, Some(report))))
    }

    /// Reads a binary or ASCII STL file into local NED metres (`axes`, `scale`,
    /// `origin_offset` as for `from_obj`); every face has `material`.
    #[staticmethod]
    #[pyo3(signature = (path, axes="enu_z_up", scale=1.0, origin_offset=(0.0, 0.0, 0.0), material=None))]
    fn from_stl(
        py: Python<'_>,
        path: PathBuf,
        axes: &str,
        scale: f64,
        origin_offset: (f64, f64, f64),
        material: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let material = match material {
            Some(m) => material_arg(m)?,
            None => Material::Opaque,
        };
        let s = settings(
            axes,
            scale,
            [origin_offset.0, origin_offset.1, origin_offset.2],
            Some(material),
        )?;
        let bytes = read_file(&path)?;
        let label = path.display().to_string();
        let (mesh, report) = py
            .detach(|| fathom_map::stl::parse_stl(&bytes, &s))
            .map_err(|e| PyValueError::new_err(e.in_file(label).to_string()))?;
        Ok(py.detach(|| Self::new(mesh, Some(report))))
    }

    /// A world from arrays already in local NED metres: `vertices` `(V, 3)` float,
    /// `triangles` `(T, 3)` vertex indices, `materials` `(T,)` codes (default opaque).
    /// The mesh is cleaned like a file's (degenerate and duplicate triangles dropped),
    /// so `World.triangles` may differ from `triangles`.
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, materials=None))]
    fn from_arrays(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        materials: Option<Vec<i64>>,
    ) -> PyResult<Self> {
        let v: Vec<Vector3<f64>> = points("vertices", vertices)?
            .into_iter()
            .map(Vector3::from)
            .collect();
        let t = points("triangles", triangles)?;
        let mut tris = Vec::with_capacity(t.len());
        for (i, row) in t.iter().enumerate() {
            let mut idx = [0u32; 3];
            for (k, &x) in row.iter().enumerate() {
                if x.fract() != 0.0 || x < 0.0 || x > f64::from(u32::MAX) {
                    return Err(PyValueError::new_err(format!(
                        "triangles: row {i} has the index {x}, expected a non-negative integer"
                    )));
                }
                idx[k] = x as u32;
            }
            tris.push(idx);
        }
        let mats = match materials {
            None => vec![Material::Opaque; tris.len()],
            Some(codes) => codes
                .into_iter()
                .map(material_from_code)
                .collect::<PyResult<Vec<_>>>()?,
        };
        let (mesh, _) =
            TriMesh::new(v, tris, mats).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(py.detach(|| Self::new(mesh, None)))
    }

    /// Number of triangles.
    fn __len__(&self) -> usize {
        self.mesh.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "fathom.World({} triangles, {} vertices)",
            self.mesh.len(),
            self.mesh.vertices().len()
        )
    }

    /// Vertices, NED metres, float64 `(V, 3)`.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat: Vec<f64> = self
            .mesh
            .vertices()
            .iter()
            .flat_map(|v| [v.x, v.y, v.z])
            .collect();
        Ok(PyArray1::from_vec(py, flat)
            .reshape([self.mesh.vertices().len(), 3])?
            .into_any())
    }

    /// Triangles as vertex indices, int64 `(T, 3)`.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat: Vec<i64> = self
            .mesh
            .triangles()
            .iter()
            .flat_map(|t| t.map(i64::from))
            .collect();
        Ok(PyArray1::from_vec(py, flat)
            .reshape([self.mesh.len(), 3])?
            .into_any())
    }

    /// Material code of each triangle, int32 `(T,)`.
    #[getter]
    fn materials<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let codes: Vec<i32> = self
            .mesh
            .materials()
            .iter()
            .map(|&m| material_code(m))
            .collect();
        PyArray1::from_vec(py, codes).into_any()
    }

    /// Bounding box `(lo, hi)` as two `(3,)` arrays, or `None` for an empty world.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyTuple>>> {
        self.mesh
            .bounds()
            .map(|(lo, hi)| {
                PyTuple::new(
                    py,
                    [
                        PyArray1::from_slice(py, lo.as_slice()),
                        PyArray1::from_slice(py, hi.as_slice()),
                    ],
                )
            })
            .transpose()
    }

    /// What reading the file did (faces read, polygons triangulated, degenerate and
    /// duplicate triangles skipped, welded vertices, open edges); `None` for
    /// `from_arrays`.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(r) = &self.report else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("faces_read", r.faces_read)?;
        d.set_item("polygons_triangulated", r.polygons_triangulated)?;
        d.set_item("ignored_elements", r.ignored_elements)?;
        d.set_item("triangles_in", r.mesh.triangles_in)?;
        d.set_item("triangles_kept", r.mesh.triangles_kept)?;
        d.set_item("degenerate_skipped", r.mesh.degenerate_skipped)?;
        d.set_item("duplicate_skipped", r.mesh.duplicate_skipped)?;
        d.set_item("vertices_welded", r.mesh.vertices_welded)?;
        d.set_item("non_manifold_edges", r.mesh.non_manifold_edges)?;
        d.set_item("boundary_edges", r.mesh.boundary_edges)?;
        Ok(Some(d))
    }

    /// Casts the rays `origins[i] + t directions[i]` (`(N, 3)` arrays, NED metres;
    /// directions need not be unit) and returns the closest hit of each with
    /// `1e-9 < t <= max_range` (a number or an `(N,)` array; `inf`: no limit).
    /// `threads`: worker threads (default: all cores); the result does not depend on
    /// it. The GIL is released while casting.
    #[pyo3(signature = (origins, directions, max_range=None, threads=None))]
    fn cast(
        &self,
        py: Python<'_>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        max_range: Option<&Bound<'_, PyAny>>,
        threads: Option<usize>,
    ) -> PyResult<RayHits> {
        let rays = rays(origins, directions, max_range)?;
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads must be at least 1"));
        }
        let caster = &self.caster;
        let hits = py.detach(|| -> Result<Vec<Option<RayHit>>, String> {
            let mut hits = vec![None; rays.len()];
            let work = |hits: &mut [Option<RayHit>]| {
                rays.par_chunks(CHUNK)
                    .zip(hits.par_chunks_mut(CHUNK))
                    .try_for_each(|(r, h)| caster.cast_batch(r, h))
                    .map_err(|e| e.to_string())
            };
            match threads {
                None => work(&mut hits)?,
                Some(n) => rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| format!("cannot start {n} threads: {e}"))?
                    .install(|| work(&mut hits))?,
            }
            Ok(hits)
        });
        let hits = hits.map_err(PyValueError::new_err)?;
        let n = hits.len();
        let mut ranges = Vec::with_capacity(n);
        let mut normals = Vec::with_capacity(3 * n);
        let mut materials = Vec::with_capacity(n);
        let mut triangles = Vec::with_capacity(n);
        let mut hit = Vec::with_capacity(n);
        for h in &hits {
            match h {
                Some(h) => {
                    ranges.push(h.range);
                    normals.extend_from_slice(h.normal_in_nav.as_slice());
                    materials.push(material_code(h.material));
                    triangles.push(i64::from(h.triangle));
                    hit.push(true);
                }
                None => {
                    ranges.push(f64::INFINITY);
                    normals.extend_from_slice(&[f64::NAN; 3]);
                    materials.push(MATERIAL_MISS);
                    triangles.push(-1);
                    hit.push(false);
                }
            }
        }
        Ok(RayHits {
            ranges: PyArray1::from_vec(py, ranges).into_any().unbind(),
            normals: PyArray1::from_vec(py, normals)
                .reshape([n, 3])?
                .into_any()
                .unbind(),
            materials: PyArray1::from_vec(py, materials).into_any().unbind(),
            triangles: PyArray1::from_vec(py, triangles).into_any().unbind(),
            hit: PyArray1::from_vec(py, hit).into_any().unbind(),
            len: n,
        })
    }

    /// One ray through the caster's scalar call (`RayCaster::cast`): `None` for a
    /// miss, else `(range, normal (3,), material code, triangle index)`. Invalid rays
    /// follow the caster's own rule (a miss), not `cast`'s checks.
    #[pyo3(signature = (origin, direction, max_range=f64::INFINITY))]
    fn cast_one<'py>(
        &self,
        py: Python<'py>,
        origin: (f64, f64, f64),
        direction: (f64, f64, f64),
        max_range: f64,
    ) -> PyResult<Option<Bound<'py, PyTuple>>> {
        let o = Vector3::new(origin.0, origin.1, origin.2);
        let d = Vector3::new(direction.0, direction.1, direction.2);
        self.caster
            .cast(&o, &d, max_range)
            .map(|h| {
                (
                    h.range,
                    PyArray1::from_slice(py, h.normal_in_nav.as_slice()),
                    material_code(h.material),
                    i64::from(h.triangle),
                )
                    .into_pyobject(py)
            })
            .transpose()
    }
}
