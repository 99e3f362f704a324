//! Python bindings of fathom: the extension module `fathom` (built by maturin from
//! `python/pyproject.toml`; the type stubs are `python/fathom.pyi`).
//!
//! - [`run`]: `fathom.run` / `fathom.check` / `fathom.preset` / `fathom.experiments`:
//!   any scenario through the experiment driver of `fathom-sim`, the summary as Python
//!   objects and the run's CSV series as numpy arrays, with the GIL released;
//! - [`kalman`]: `fathom.KalmanFilter`, FilterPy's attribute names on the Kalman core
//!   of `fathom-estimators` (size dispatch in [`kalman_core`]);
//! - [`world`]: `fathom.World`, a triangle mesh from OBJ / STL and batch-parallel ray
//!   casting with the BVH caster of `fathom-map`.
//!
//! Errors never panic across the boundary: bad arguments and invalid scenarios raise
//! `ValueError` (or `TypeError` from pyo3's own argument conversion), unreadable files
//! `OSError`, failures while running `RuntimeError`; messages are the library
//! crates' own, on one line.

mod arrays;
mod csv;
pub mod kalman;
pub mod kalman_core;
pub mod run;
pub mod world;

use pyo3::prelude::*;

/// fathom: navigation sensor simulation and estimators (Rust), from Python.
#[pymodule(name = "fathom")]
fn fathom_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::check, m)?)?;
    m.add_function(wrap_pyfunction!(run::preset, m)?)?;
    m.add_function(wrap_pyfunction!(run::experiments, m)?)?;
    m.add_class::<run::RunResult>()?;
    m.add_class::<kalman::KalmanFilter>()?;
    m.add_class::<world::World>()?;
    m.add_class::<world::RayHits>()?;
    m.add("MATERIAL_MISS", world::MATERIAL_MISS)?;
    m.add("MATERIAL_OPAQUE", world::MATERIAL_OPAQUE)?;
    m.add("MATERIAL_GLASS", world::MATERIAL_GLASS)?;
    m.add("MATERIAL_OTHER_BASE", world::MATERIAL_OTHER_BASE)?;
    m.add("MAX_FIXED_DIM_X", kalman_core::MAX_FIXED_N)?;
    m.add("MAX_FIXED_DIM_Z", kalman_core::MAX_FIXED_M)?;
    Ok(())
}
